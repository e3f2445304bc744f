"""Poses as the environments show them: position and quaternion (x, y, z, qx, qy, qz, qw)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from armfleet.messages import FloatArray

#: Length of a pose vector: position [m] and unit quaternion, scalar last.
POSE_SIZE = 7


def pose_vector(pose: FloatArray) -> FloatArray:
    """The 4x4 ``pose`` as (x, y, z, qx, qy, qz, qw) [m], with qw >= 0 (one of the two
    quaternions of a rotation, so that equal rotations give equal vectors)."""
    quaternion = pin.Quaternion(np.asarray(pose[:3, :3], dtype=float)).coeffs()  # x, y, z, w
    if quaternion[3] < 0:
        quaternion = -quaternion
    return np.concatenate([pose[:3, 3], quaternion])


def rotation_from_rpy(delta: FloatArray) -> FloatArray:
    """Rz(yaw) Ry(pitch) Rx(roll) of ``delta = (roll, pitch, yaw)`` [rad]."""
    return np.asarray(pin.rpy.rpyToMatrix(np.asarray(delta, dtype=float)), dtype=float)


def moved(pose: FloatArray, delta: FloatArray) -> FloatArray:
    """``pose`` (4x4, in the world) moved by ``delta = (dx, dy, dz, droll, dpitch, dyaw)``:
    translated along the world axes [m] and turned about the world axes through its own
    origin [rad] (R' = R(delta) R)."""
    result = np.array(pose, dtype=float)
    result[:3, 3] += delta[:3]
    result[:3, :3] = rotation_from_rpy(delta[3:]) @ result[:3, :3]
    return result
