"""ROS 2 nodes drive the arms as they drive joint_trajectory_controller (issue 29): a
FollowJointTrajectory goal is followed within its tolerances, wrong joint names end with
INVALID_JOINTS, a new goal preempts, cancel brings the arm to rest, the joint_trajectory
topic moves toby, forward commands and the gripper action work, and a node killed
mid-goal leaves the world and the other arm as they were. The arm's state is read
through the live API, not through ROS."""

from __future__ import annotations

import json
import signal
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armfleet
from tests.remote_world import WorldProcess, wait_until
from tests.ros_world import ros_node, serve, start_ros_node

# action_msgs/GoalStatus
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
BOB = [f"bob_panda_joint{i}" for i in range(1, 8)]
TOBY = [f"toby_panda_joint{i}" for i in range(1, 8)]
STEP = np.array([0.4, -0.3, 0.3, -0.4, 0.3, 0.4, -0.5])


@pytest.fixture
def served(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[WorldProcess, int]]:
    """bob and toby served to ROS 2 (tests/ros_world.py), and the domain."""
    yield from serve(tmp_path, monkeypatch)


def _trajectory(
    names: list[str], start: np.ndarray, *stops: tuple[float, np.ndarray]
) -> dict[str, Any]:
    return {
        "joint_names": names,
        "points": [
            {"positions": (start + delta).tolist(), "time_from_start": t} for t, delta in stops
        ],
    }


def test_a_goal_is_followed_within_its_tolerances(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        # Given in another joint order than the arm's: the controller reorders.
        order = [6, 0, 5, 1, 4, 2, 3]
        stops = [(1.0, 0.5 * STEP), (2.0, STEP)]
        trajectory = {
            "joint_names": [BOB[i] for i in order],
            "points": [
                {"positions": (start + d)[order].tolist(), "time_from_start": t} for t, d in stops
            ],
        }
        tolerance = [{"name": n, "position": 0.02} for n in BOB]
        [result] = ros_node(
            domain,
            "goal",
            {
                "arm": "bob",
                "goals": [
                    {
                        "trajectory": trajectory,
                        "path_tolerance": tolerance,
                        "goal_tolerance": tolerance,
                    }
                ],
            },
        )
        assert result["status"] == SUCCEEDED, result
        assert result["error_code"] == 0
        assert result["feedback"] > 10  # at the publication rate, over 2 s
        np.testing.assert_allclose(bob.positions, start + STEP, atol=0.02)


def test_wrong_joint_names_end_with_invalid_joints_and_nothing_moves(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        wrong = [*BOB[:6], "bob_panda_joint9"]
        [result] = ros_node(
            domain,
            "goal",
            {"arm": "bob", "goals": [{"trajectory": _trajectory(wrong, start, (1.0, STEP))}]},
        )
        assert result["status"] == ABORTED
        assert result["error_code"] == -2  # INVALID_JOINTS
        assert "bob_panda_joint9" in result["error_string"]
        assert "\n" not in result["error_string"]
        np.testing.assert_allclose(bob.positions, start, atol=1e-4)


def test_a_new_goal_preempts_the_one_followed(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        first = _trajectory(BOB, start, (4.0, STEP))
        second = _trajectory(BOB, start, (1.5, -0.5 * STEP))
        results = ros_node(
            domain,
            "goal",
            {"arm": "bob", "goals": [{"trajectory": first}, {"trajectory": second, "after": 1.0}]},
        )
        assert results[0]["status"] == ABORTED, results
        assert "new incoming action" in results[0]["error_string"]
        assert results[1]["status"] == SUCCEEDED, results
        np.testing.assert_allclose(bob.positions, start - 0.5 * STEP, atol=0.02)


def test_cancel_brings_the_arm_to_rest_short_of_its_goal(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        goal = _trajectory(BOB, start, (4.0, STEP))
        [result] = ros_node(
            domain, "goal", {"arm": "bob", "goals": [{"trajectory": goal}], "cancel_after": 1.0}
        )
        assert result["status"] == CANCELED, result
        state = bob.wait(timeout=30)  # it holds where it stopped
        assert np.max(np.abs(state.velocity[:7])) < 1e-2
        moved = np.abs(bob.positions - start)
        assert np.max(moved) > 0.01  # it had started
        assert np.max(np.abs(bob.positions - (start + STEP))) > 0.1  # it did not go on


def test_a_trajectory_published_on_the_topic_moves_toby(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        toby, bob = client.arm("toby"), client.arm("bob")
        start, bob_start = toby.positions, bob.positions
        ros_node(
            domain,
            "publish",
            {"arm": "toby", "trajectory": _trajectory(TOBY, start, (1.0, STEP))},
        )
        assert wait_until(
            lambda: np.max(np.abs(toby.positions - (start + STEP))) < 2e-3, timeout=30
        )
        np.testing.assert_allclose(bob.positions, bob_start, atol=1e-4)


def test_forward_commands_and_the_gripper_action(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        target = bob.positions - 0.5 * STEP
        ros_node(domain, "forward", {"arm": "bob", "values": target.tolist()})
        assert wait_until(lambda: np.max(np.abs(bob.positions - target)) < 2e-3, timeout=30)
        closed = ros_node(domain, "gripper", {"arm": "bob", "position": 0.02, "max_effort": 0.0})
        assert closed["status"] == SUCCEEDED and closed["reached_goal"], closed
        assert abs(closed["position"] - 0.02) < 2e-3
        assert abs(bob.gripper.width - 0.02) < 2e-3


def test_a_node_killed_mid_goal_leaves_the_world_and_the_other_arm(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob, toby = client.arm("bob"), client.arm("toby")
        start, toby_start = bob.positions, toby.positions
        node = start_ros_node(
            domain,
            "goal",
            {"arm": "bob", "goals": [{"trajectory": _trajectory(BOB, start, (3.0, STEP))}]},
        )
        try:
            assert wait_until(lambda: np.max(np.abs(bob.positions - start)) > 0.01, timeout=60)
        finally:
            node.send_signal(signal.SIGKILL)
            node.wait(timeout=30)
        # The goal goes on without its client (as in ROS); the world keeps stepping.
        before = client.info().time_s
        assert wait_until(lambda: np.max(np.abs(bob.positions - (start + STEP))) < 0.02, timeout=30)
        assert client.info().time_s > before
        np.testing.assert_allclose(toby.positions, toby_start, atol=1e-4)
        # Another node is served as before.
        time.sleep(0.1)
        [result] = ros_node(
            domain,
            "goal",
            {"arm": "bob", "goals": [{"trajectory": _trajectory(BOB, start, (1.5, 0 * STEP))}]},
        )
        assert result["status"] == SUCCEEDED, result


def test_a_goal_stamped_in_the_future_starts_then(served) -> None:
    """joint_trajectory_controller starts a trajectory at its header stamp: before it the
    arm holds, after it the arm follows and the goal succeeds."""
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        stamp = client.info().time_s + 6.0
        trajectory = _trajectory(BOB, start, (1.0, STEP)) | {"stamp": stamp}
        node = start_ros_node(domain, "goal", {"arm": "bob", "goals": [{"trajectory": trajectory}]})
        try:
            held = []
            while client.info().time_s < stamp - 0.2:
                held.append(np.abs(bob.positions - start).max())
                time.sleep(0.1)
            out, err = node.communicate(timeout=120)
        finally:
            if node.poll() is None:
                node.kill()
        assert node.returncode == 0, err[-2000:]
        assert len(held) > 10 and max(held) < 1e-4  # it waited for its stamp
        [result] = json.loads(out.strip().splitlines()[-1])
        assert result["status"] == SUCCEEDED, result
        np.testing.assert_allclose(bob.positions, start + STEP, atol=0.02)


def test_tolerances_out_of_reach_end_with_their_codes(served) -> None:
    """A path tolerance tighter than the arm tracks stops it with PATH_TOLERANCE_VIOLATED;
    a goal tolerance tighter than it holds ends GOAL_TOLERANCE_VIOLATED after
    goal_time_tolerance."""
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        start = bob.positions
        tight = [{"name": n, "position": 1e-12} for n in BOB]
        results = ros_node(
            domain,
            "goal",
            {
                "arm": "bob",
                "goals": [
                    {"trajectory": _trajectory(BOB, start, (2.0, STEP)), "path_tolerance": tight},
                    {
                        "trajectory": _trajectory(BOB, start, (1.0, 0.2 * STEP)),
                        "goal_tolerance": tight,
                        "goal_time_tolerance": 0.2,
                        "after": 3.0,
                    },
                ],
            },
        )
        path, goal = results
        assert path["status"] == ABORTED and path["error_code"] == -4, path
        assert "left its path" in path["error_string"]
        assert goal["status"] == ABORTED and goal["error_code"] == -5, goal
        assert "from its goal" in goal["error_string"]
