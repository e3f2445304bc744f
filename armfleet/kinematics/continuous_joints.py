"""Continuous joints: revolute joints with no position limit, one angle each, never wrapped.

URDF's ``continuous`` joint turns without end. Pinocchio models it with two coordinates,
``(cos q, sin q)``; armfleet keeps one position per joint everywhere (the controllers, the
compiled kernel, the joint memory, the planner), and PyBullet simulates it as a revolute
joint with no limit whose angle runs on past ±pi (7.0 rad is 7.0 rad, not 0.72). So the
text Pinocchio reads has each continuous joint as a revolute one, and
:class:`~armfleet.kinematics.ArmKinematics` gives it the limits -inf and +inf: limit
checks and clamps pass it untouched. The angle is the joint's true, unwrapped one; only
where a choice between equivalent angles is made (an IK solution, a planned goal) is the
one nearest the present angle taken, :func:`nearest_turn`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import numpy.typing as npt

from armfleet.messages import FloatArray

#: The URDF joint type with no position limit.
CONTINUOUS = "continuous"


def continuous_joint_names(urdf: str) -> frozenset[str]:
    """Names of the ``continuous`` joints of ``urdf`` (empty if it is not XML: the model
    builder then reports the problem)."""
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError:
        return frozenset()
    return frozenset(
        joint.get("name", "") for joint in robot.iter("joint") if joint.get("type") == CONTINUOUS
    )


def as_revolute(urdf: str) -> str:
    """``urdf`` with every continuous joint a revolute one, for Pinocchio's one coordinate.

    URDF requires a revolute joint's ``<limit>``: one is added where the continuous joint
    has none, with zero bounds (the caller replaces the bounds with -inf/+inf, and takes
    the effort and velocity limits from the unchanged text).
    """
    robot = ET.fromstring(urdf)
    for joint in robot.iter("joint"):
        if joint.get("type") != CONTINUOUS:
            continue
        joint.set("type", "revolute")
        limit = joint.find("limit")
        if limit is None:
            limit = ET.SubElement(joint, "limit", {"effort": "0", "velocity": "0"})
        limit.set("lower", "0")
        limit.set("upper", "0")
    return ET.tostring(robot, encoding="unicode")


def nearest_turn(
    values: FloatArray, reference: FloatArray, continuous: npt.NDArray[np.bool_]
) -> FloatArray:
    """``values`` with each continuous joint's angle replaced by its equivalent (a whole
    number of turns away) nearest ``reference``, within [-pi, pi) of it; a new array.

    The other joints keep their values.
    """
    result = np.array(values, dtype=float)
    offset = result[continuous] - reference[continuous]
    result[continuous] = reference[continuous] + (offset + np.pi) % (2.0 * np.pi) - np.pi
    return result


def one_turn_bounds(lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Finite bounds to draw positions from: the limits, and [-pi, pi] (one whole turn)
    for a joint with none. New arrays."""
    bounded = np.isfinite(lower) & np.isfinite(upper)
    return np.where(bounded, lower, -np.pi), np.where(bounded, upper, np.pi)
