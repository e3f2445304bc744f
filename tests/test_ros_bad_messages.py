"""Bad messages from ROS 2 nodes are refused as the live API refuses them, and nothing
moves (issue 29): NaN, wrong lengths, unknown joints, empty trajectories, times going
backwards, and the like, on the action, the topic and the forward command. The arm's
joints are read through the live API."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armfleet
from tests.remote_world import WorldProcess
from tests.ros_world import ros_node, serve

ABORTED = 6
INVALID_GOAL, INVALID_JOINTS, OLD_HEADER_TIMESTAMP = -1, -2, -3
BOB = [f"bob_panda_joint{i}" for i in range(1, 8)]
NAN = float("nan")


@pytest.fixture
def served(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[WorldProcess, int]]:
    """bob and toby served to ROS 2 (tests/ros_world.py), and the domain."""
    yield from serve(tmp_path, monkeypatch)


def _point(positions: list[float], t: float, **extra: list[float]) -> dict[str, Any]:
    return {"positions": positions, "time_from_start": t, **extra}


def _cases(q: list[float]) -> list[tuple[str, dict[str, Any], int, str]]:
    """(what, trajectory, error code, a word of the reason)."""
    moved = [v + 0.2 for v in q]
    return [
        ("a NaN position", {"joint_names": BOB, "points": [_point([NAN, *q[1:]], 1.0)]},
         INVALID_GOAL, "finite"),
        ("six positions for seven joints", {"joint_names": BOB, "points": [_point(q[:6], 1.0)]},
         INVALID_GOAL, "one per joint"),
        ("an unknown joint", {"joint_names": [*BOB[:6], "bob_panda_finger_joint1"],
         "points": [_point(moved, 1.0)]}, INVALID_JOINTS, "bob_panda_finger_joint1"),
        ("a joint named twice", {"joint_names": [*BOB[:6], BOB[0]],
         "points": [_point(moved, 1.0)]}, INVALID_JOINTS, "once"),
        ("no points", {"joint_names": BOB, "points": []}, INVALID_GOAL, "no points"),
        ("times going backwards", {"joint_names": BOB,
         "points": [_point(moved, 2.0), _point(q, 1.0)]}, INVALID_GOAL, "increase"),
        ("a first point at time 0", {"joint_names": BOB, "points": [_point(moved, 0.0)]},
         INVALID_GOAL, "> 0"),
        ("velocities of the wrong length", {"joint_names": BOB,
         "points": [_point(moved, 1.0, velocities=[0.0] * 3)]}, INVALID_GOAL, "velocities"),
        ("an infinite velocity", {"joint_names": BOB,
         "points": [_point(moved, 1.0, velocities=[float("inf"), *[0.0] * 6])]},
         INVALID_GOAL, "finite"),
        ("a target outside the joint limits", {"joint_names": BOB,
         "points": [_point([q[0] + 9.0, *q[1:]], 1.0)]}, INVALID_GOAL, "limits"),
        ("faster than the arm can go", {"joint_names": BOB,
         "points": [_point([q[0] + 1.5, *q[1:]], 0.05)]}, INVALID_GOAL, "limits"),
        ("every point in the past", {"joint_names": BOB, "stamp": 0.5,
         "points": [_point(moved, 0.1)]}, OLD_HEADER_TIMESTAMP, "past"),
    ]  # fmt: skip


def test_bad_goals_end_with_the_controllers_codes_and_nothing_moves(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        cases = _cases(start.tolist())
        goals = [
            {"trajectory": trajectory, "after": 0.1 * i}
            for i, (_, trajectory, _, _) in enumerate(cases)
        ]
        results = ros_node(domain, "goal", {"arm": "bob", "goals": goals})
        for (what, _, code, word), result in zip(cases, results, strict=True):
            assert result["status"] == ABORTED, (what, result)
            assert result["error_code"] == code, (what, result)
            text = result["error_string"]
            assert word in text and "\n" not in text and text.startswith("bob:"), (what, text)
        np.testing.assert_allclose(bob.positions, start, atol=1e-4)


@pytest.mark.parametrize(
    ("what", "values"),
    [("a NaN", [NAN] * 7), ("six values", [0.0] * 6), ("no values", [])],
)
def test_bad_forward_commands_and_topic_trajectories_move_nothing(served, what, values) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        ros_node(domain, "forward", {"arm": "bob", "values": values})
        bad = _cases(start.tolist())[len(values) % 3]  # a bad trajectory on the topic too
        ros_node(domain, "publish", {"arm": "bob", "trajectory": bad[1]})
        time.sleep(0.5)  # the world has taken both (the node waited for delivery)
        assert sorted(client.info().arms) == ["bob", "toby"]
        np.testing.assert_allclose(bob.positions, start, atol=1e-4)
    assert sum("refused" in line for line in world.stderr) >= 2, world.stderr[-5:]
