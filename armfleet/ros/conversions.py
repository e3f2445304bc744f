"""armfleet's messages as ROS 2's: stamps in simulated time, transforms, joint states."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pinocchio as pin
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage

from armfleet import messages

_NS = 1_000_000_000


def ros_time(seconds: float) -> Time:
    """``builtin_interfaces/Time`` of ``seconds`` of simulated time (>= 0)."""
    total = round(seconds * _NS)
    return Time(sec=total // _NS, nanosec=total % _NS)


def to_seconds(stamp: Time | Duration) -> float:
    """Seconds of a ``Time`` or ``Duration`` (negative durations included)."""
    return float(stamp.sec + stamp.nanosec / _NS)


def joint_state(state: messages.JointState) -> JointState:
    """``sensor_msgs/JointState`` of an arm's measured joint state."""
    message = JointState()
    message.header.stamp = ros_time(state.stamp)
    message.name = list(state.name)
    message.position = state.position.tolist()
    message.velocity = state.velocity.tolist()
    message.effort = state.effort.tolist()
    return message


def transforms(message: messages.TFMessage) -> TFMessage:
    """``tf2_msgs/TFMessage`` of armfleet's transforms (4x4 matrices)."""
    return tf_message(message.transforms)


def tf_message(stamped: Iterable[messages.TransformStamped]) -> TFMessage:
    return TFMessage(transforms=[_transform(t) for t in stamped])


def _transform(stamped: messages.TransformStamped) -> TransformStamped:
    out = TransformStamped()
    out.header.stamp = ros_time(stamped.stamp)
    out.header.frame_id = stamped.frame_id
    out.child_frame_id = stamped.child_frame_id
    matrix = np.asarray(stamped.matrix, dtype=float)
    translation = out.transform.translation
    translation.x, translation.y, translation.z = (float(v) for v in matrix[:3, 3])
    x, y, z, w = pin.Quaternion(matrix[:3, :3]).normalized().coeffs()
    rotation = out.transform.rotation
    rotation.x, rotation.y, rotation.z, rotation.w = float(x), float(y), float(z), float(w)
    return out


def is_zero(stamp: Time) -> bool:
    return bool(stamp.sec == 0 and stamp.nanosec == 0)
