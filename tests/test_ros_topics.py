"""What a ROS 2 node subscribing to an armfleet world sees (issue 29): joint states equal
to the world's, on ``/clock`` time, and a ``/tf`` + ``/tf_static`` tree that agrees with
forward kinematics computed here by Pinocchio from the ``robot_description`` the node
received (an independent model of the same arm), spawn poses included."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from tests.remote_world import WorldProcess
from tests.ros_world import ros_node, serve

RATE_HZ = 100.0


@pytest.fixture
def served(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[WorldProcess, int]]:
    """bob and toby served to ROS 2 (tests/ros_world.py), and the domain."""
    yield from serve(tmp_path, monkeypatch)


def _matrix(entry: dict[str, Any]) -> np.ndarray:
    x, y, z, w = entry["rotation"]
    pose = np.eye(4)
    pose[:3, :3] = pin.Quaternion(w, x, y, z).toRotationMatrix()
    pose[:3, 3] = entry["translation"]
    return pose


def _world_pose(frame: str, tree: dict[str, dict[str, Any]]) -> np.ndarray:
    """``world -> frame`` by walking the received transforms up to ``world``."""
    pose = np.eye(4)
    while frame != "world":
        entry = tree[frame]
        pose = _matrix(entry) @ pose
        frame = entry["parent"]
    return pose


def test_joint_states_and_tf_equal_the_world_on_clock_time(served) -> None:
    world, domain = served
    with armfleet.connect(world.address) as client:
        bob = client.arm("bob")
        target = bob.positions + np.array([0.3, -0.2, 0.2, -0.3, 0.2, 0.3, -0.4])
        bob.move_to(target)
        bob.wait(timeout=60)
        seen = ros_node(domain, "watch", {"arm": "bob", "seconds": 1.0})
        held = bob.positions
    state = seen["joint_state"]
    names = state["name"]
    assert names[:7] == [f"bob_panda_joint{i}" for i in range(1, 8)]
    # At rest the arm holds: the node's last joint state is the world's, to the hold.
    np.testing.assert_allclose(state["position"][:7], held, atol=1e-6)
    np.testing.assert_allclose(state["position"][:7], target, atol=2e-3)
    # Simulated time: /clock advances by one publication period at a time, and the
    # joint state is stamped with it (within one period of the last clock received).
    clocks = np.array(seen["clocks"])
    steps = np.diff(clocks)
    assert np.all(steps > 0)
    assert np.median(steps) == pytest.approx(1.0 / RATE_HZ, abs=1e-6)
    assert abs(state["stamp"] - seen["clock_when_state"]) <= 1.0 / RATE_HZ + 1e-9
    # The tree: every link bob's URDF has, placed as Pinocchio puts it for these joints.
    tree = seen["tf_static"] | seen["tf"]
    model = pin.buildModelFromXML(seen["robot_description"])
    data = model.createData()
    q = pin.neutral(model)
    for name, value in zip(names, state["position"], strict=True):
        joint = model.joints[model.getJointId(name)]
        q[joint.idx_q] = value
    pin.framesForwardKinematics(model, data, q)
    base = _world_pose("bob_base_link", tree)
    base_in_model = data.oMf[model.getFrameId("bob_base_link")].homogeneous
    checked = 0
    for frame in model.frames:
        if frame.type != pin.FrameType.BODY or frame.name not in tree:
            continue
        expected = (
            base @ np.linalg.inv(base_in_model) @ data.oMf[model.getFrameId(frame.name)].homogeneous
        )
        np.testing.assert_allclose(
            _world_pose(frame.name, tree), expected, atol=1e-6, err_msg=frame.name
        )
        checked += 1
    assert checked >= 10  # link0..link8, hand, fingers


def test_tf_static_carries_both_spawn_poses(served) -> None:
    """The old setup's bug: spawn poses missing from TF. Here world -> <arm>_base_link is
    on /tf_static for both arms, at their spawn positions."""
    _, domain = served
    seen = ros_node(domain, "watch", {"arm": "toby", "seconds": 0.2})
    static = seen["tf_static"]
    for arm, x in (("bob", 0.0), ("toby", 1.0)):
        entry = static[f"{arm}_base_link"]
        assert entry["parent"] == "world"
        np.testing.assert_allclose(entry["translation"], [x, 0.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(entry["rotation"], [0.0, 0.0, 0.0, 1.0], atol=1e-12)
    assert (
        "<robot" in seen["robot_description"] and "toby_panda_joint1" in seen["robot_description"]
    )
