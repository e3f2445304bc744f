"""The streamed messages' CDR bytes (armfleet/ros/cdr.py) are what rclpy's own
serializer gives for the same messages built as rclpy objects: the same length, and
rclpy reads back every field exactly. (Not byte for byte: rclpy's serializer leaves its
alignment padding uninitialised, where armfleet writes zeros.)"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

pytest.importorskip("rclpy", reason="needs armfleet[ros]")
pytest.importorskip("tf2_msgs", reason="needs ros_interfaces/ built")

from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState as RosJointState
from tf2_msgs.msg import TFMessage as RosTFMessage

from armfleet import messages
from armfleet.ros import conversions
from armfleet.ros.cdr import JointStateLayout, TfLayout


def _pose(rng: np.random.Generator) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = pin.Quaternion(*rng.normal(size=4)).normalized().toRotationMatrix()
    pose[:3, 3] = rng.normal(size=3)
    return pose


@pytest.mark.parametrize("seed", range(5))
def test_tf_bytes_equal_rclpys_serialization(seed: int) -> None:
    rng = np.random.default_rng(seed)
    names = ["world", "bob_base_link", "b", "toby_panda_link7", "x" * int(rng.integers(1, 9))]
    frames = [(names[i % len(names)], names[(i + 1) % len(names)]) for i in range(1 + seed * 3)]
    stamp = float(rng.uniform(0, 1e5))
    message = messages.TFMessage(
        tuple(messages.TransformStamped(stamp, a, b, _pose(rng)) for a, b in frames)
    )
    ours = TfLayout(frames).serialize(message)
    reference = conversions.transforms(message)
    assert len(ours) == len(serialize_message(reference))
    assert deserialize_message(ours, RosTFMessage) == reference


@pytest.mark.parametrize("joints", [0, 1, 7, 9])
def test_joint_state_bytes_equal_rclpys_serialization(joints: int) -> None:
    rng = np.random.default_rng(joints)
    names = tuple(f"bob_panda_joint{i}" + "_" * i for i in range(joints))
    state = messages.JointState(
        float(rng.uniform(0, 100)), names, rng.normal(size=joints), rng.normal(size=joints),
        rng.normal(size=joints),
    )  # fmt: skip
    ours = JointStateLayout(names).serialize(state)
    reference = conversions.joint_state(state)
    if joints:  # (with no joints rclpy appends 8 bytes it never reads)
        assert len(ours) == len(serialize_message(reference))
    assert deserialize_message(ours, RosJointState) == reference
