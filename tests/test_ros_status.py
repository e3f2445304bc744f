"""Arm status and contacts reach ROS 2 in standard messages (issue 29): bob driven into
the floor stops, and a node sees its ``/diagnostics`` status go from OK to WARN with the
protective stop's reason, and the contact on ``/collisions`` naming bob's link and the
floor, the same contact the world reports through the live API."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

import armfleet
from tests.remote_world import WorldProcess, wait_until
from tests.ros_world import NODE_TIMEOUT_S, serve, start_ros_node

OK, WARN = 0, 1


@pytest.fixture
def served(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[WorldProcess, int]]:
    """bob and toby served to ROS 2 (tests/ros_world.py), and the domain."""
    yield from serve(tmp_path, monkeypatch)


def test_a_protective_stop_shows_in_diagnostics_and_collisions(served) -> None:
    world, domain = served
    node = start_ros_node(domain, "monitor", {"arm": "bob", "level": WARN})
    try:
        assert node.stdout is not None
        assert node.stdout.readline().strip() == "listening"
        with armfleet.connect(world.address) as client:
            bob = client.arm("bob")
            upper = bob.joint_limits[1]
            # The shoulder forward and the elbow straight: the hand goes through the floor.
            target = bob.positions.copy()
            target[1], target[3] = upper[1] - 0.05, upper[3] - 0.05
            bob.move_to(target)
            assert wait_until(lambda: bob.mode is armfleet.ArmMode.PROTECTIVE_STOP, timeout=60)
            out, err = node.communicate(timeout=NODE_TIMEOUT_S)
    except BaseException:
        node.kill()
        raise
    assert node.returncode == 0, err[-2000:]
    seen = json.loads(out.strip().splitlines()[-1])
    levels = [status["level"] for status in seen["statuses"]]
    assert levels[0] == OK and levels[-1] == WARN
    last = seen["statuses"][-1]
    assert last["name"] == "bob: arm" and last["values"]["mode"] == "protective stop"
    assert last["message"].startswith("protective stop: ")
    assert last["values"]["reason"] and last["values"]["reason"] in last["message"]
    assert any("bob/bob_panda_" in text for text in seen["contacts"]), seen["contacts"]


def test_an_arm_that_holds_is_ok(served) -> None:
    _, domain = served
    node = start_ros_node(domain, "monitor", {"arm": "toby", "level": OK})
    out, err = node.communicate(timeout=NODE_TIMEOUT_S)
    assert node.returncode == 0, err[-2000:]
    [status, *_] = json.loads(out.strip().splitlines()[-1])["statuses"]
    assert status == {
        "level": OK,
        "name": "toby: arm",
        "message": "holding",
        "values": {
            "mode": "holding",
            "reason": "",
            "effort_limit_hits": status["values"]["effort_limit_hits"],
        },
    }
    assert len(status["values"]["effort_limit_hits"].split()) == 9  # per movable joint
