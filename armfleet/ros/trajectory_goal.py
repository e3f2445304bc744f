"""A ``JointTrajectory`` as joint_trajectory_controller takes it: checked, put in the
arm's joint order and its time, then followed and judged step by step.

Everything here runs in the world's stepping thread. The error codes are
``control_msgs/action/FollowJointTrajectory``'s; the tolerances follow
joint_trajectory_controller's rules: in a goal, a tolerance > 0 is used, 0 means the
controller's default (:class:`ControllerDefaults`), < 0 means none.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from control_msgs.action import FollowJointTrajectory

from armfleet.errors import ArmfleetError
from armfleet.messages import FloatArray
from armfleet.motion.timed_trajectory import check_waypoints
from armfleet.ros.conversions import is_zero, to_seconds

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm

_RESULT = FollowJointTrajectory.Result
SUCCESSFUL: int = _RESULT.SUCCESSFUL
INVALID_GOAL: int = _RESULT.INVALID_GOAL
INVALID_JOINTS: int = _RESULT.INVALID_JOINTS
OLD_HEADER_TIMESTAMP: int = _RESULT.OLD_HEADER_TIMESTAMP
PATH_TOLERANCE_VIOLATED: int = _RESULT.PATH_TOLERANCE_VIOLATED
GOAL_TOLERANCE_VIOLATED: int = _RESULT.GOAL_TOLERANCE_VIOLATED


@dataclass(frozen=True)
class ControllerDefaults:
    """The trajectory controller's own constraints (its ``constraints`` parameters).

    Attributes:
        goal_position_rad: how near each joint must end [rad or m].
        stopped_velocity_rad_s: how slow each joint must be to count as stopped.
        goal_time_s: how long after the trajectory's end the arm may take to get there.
    """

    goal_position_rad: float = 0.01
    stopped_velocity_rad_s: float = 0.01
    goal_time_s: float = 1.0


class Outcome(enum.Enum):
    SUCCEEDED = "succeeded"
    ABORTED = "aborted"
    CANCELED = "canceled"


@dataclass(frozen=True)
class GoalResult:
    """How a goal ended: the action's status, and its result's code and text."""

    outcome: Outcome
    error_code: int
    error_string: str


class GoalRefused(Exception):
    """A trajectory refused before anything moved, with its error code."""

    def __init__(self, error_code: int, message: str) -> None:
        super().__init__(message)
        self.error_code = error_code


@dataclass(frozen=True)
class Tolerances:
    """Per joint, in the arm's order; ``inf`` where a tolerance is not checked."""

    path_position: FloatArray
    path_velocity: FloatArray
    goal_position: FloatArray
    goal_velocity: FloatArray
    goal_time_s: float

    @classmethod
    def defaults(cls, joints: int, defaults: ControllerDefaults) -> Tolerances:
        none = np.full(joints, np.inf)
        return cls(
            none,
            none.copy(),
            np.full(joints, defaults.goal_position_rad),
            np.full(joints, defaults.stopped_velocity_rad_s),
            defaults.goal_time_s,
        )


@dataclass(frozen=True)
class PreparedTrajectory:
    """A trajectory in the arm's joint order, timed from ``start_s`` (simulated time)."""

    start_s: float
    times: FloatArray
    positions: FloatArray
    velocities: FloatArray | None
    accelerations: FloatArray | None
    tolerances: Tolerances

    @property
    def end_s(self) -> float:
        return self.start_s + float(self.times[-1])


def prepare(
    arm: Arm,
    trajectory: Any,
    now: float,
    defaults: ControllerDefaults,
    goal: Any | None = None,
) -> PreparedTrajectory:
    """Check ``trajectory`` (``trajectory_msgs/JointTrajectory``) and the tolerances of
    ``goal`` (a ``FollowJointTrajectory`` goal, or None for the topic) for ``arm``.

    Raises:
        GoalRefused: with ``INVALID_JOINTS`` (names not the arm's joints, each once),
            ``OLD_HEADER_TIMESTAMP`` (every point already in the past) or ``INVALID_GOAL``
            (no points, lengths, numbers, times, multi-DOF parts).
    """
    name = arm.name
    joints = arm.joint_names
    if goal is not None and len(goal.multi_dof_trajectory.points) > 0:
        raise GoalRefused(INVALID_GOAL, f"{name}: multi-DOF trajectories are not supported")
    order = _joint_order(name, joints, list(trajectory.joint_names))
    points = list(trajectory.points)
    if not points:
        raise GoalRefused(INVALID_GOAL, f"{name}: the trajectory has no points; give at least one")
    start = now if is_zero(trajectory.header.stamp) else to_seconds(trajectory.header.stamp)
    times = np.array([to_seconds(p.time_from_start) for p in points])
    if start < now:  # points already past are dropped, as the controller does
        kept = times > now - start
        if not np.any(kept):
            raise GoalRefused(
                OLD_HEADER_TIMESTAMP,
                f"{name}: every point of the trajectory is in the past (header stamp "
                f"{start:.6g} s, last point at {start + times[-1]:.6g} s, now {now:.6g} s)",
            )
        first = int(np.argmax(kept))
        points, times = points[first:], times[first:] - (now - start)
        start = now
    try:
        waypoints = check_waypoints(
            name,
            len(joints),
            times.tolist(),
            [list(p.positions) for p in points],
            [list(p.velocities) for p in points],
            [list(p.accelerations) for p in points],
        )
    except ArmfleetError as exc:
        raise GoalRefused(INVALID_GOAL, str(exc)) from None
    tolerances = Tolerances.defaults(len(joints), defaults)
    if goal is not None:
        tolerances = _goal_tolerances(name, joints, goal, tolerances)
    return PreparedTrajectory(
        start,
        waypoints.times,
        waypoints.positions[:, order],
        None if waypoints.velocities is None else waypoints.velocities[:, order],
        None if waypoints.accelerations is None else waypoints.accelerations[:, order],
        tolerances,
    )


def _joint_order(arm: str, joints: Sequence[str], given: list[str]) -> list[int]:
    """Column of each of the arm's joints in ``given``."""
    if sorted(given) != sorted(joints):
        raise GoalRefused(
            INVALID_JOINTS,
            f"{arm}: joint_names {given} are not {arm}'s joints; give each of "
            f"{', '.join(joints)} once, in any order",
        )
    return [given.index(joint) for joint in joints]


def _goal_tolerances(arm: str, joints: Sequence[str], goal: Any, base: Tolerances) -> Tolerances:
    path_position, path_velocity = base.path_position.copy(), base.path_velocity.copy()
    goal_position, goal_velocity = base.goal_position.copy(), base.goal_velocity.copy()
    for field, position, velocity in (
        ("path_tolerance", path_position, path_velocity),
        ("goal_tolerance", goal_position, goal_velocity),
    ):
        for tolerance in getattr(goal, field):
            if tolerance.name not in joints:
                raise GoalRefused(
                    INVALID_JOINTS,
                    f"{arm}: {field} names {tolerance.name!r}, not one of {', '.join(joints)}",
                )
            index = joints.index(tolerance.name)
            for values, given in ((position, tolerance.position), (velocity, tolerance.velocity)):
                if not np.isfinite(given):
                    raise GoalRefused(
                        INVALID_GOAL, f"{arm}: {field} of {tolerance.name} is {given}"
                    )
                _apply(values, index, given)
    goal_time = to_seconds(goal.goal_time_tolerance)
    if goal_time < 0.0:
        raise GoalRefused(INVALID_GOAL, f"{arm}: goal_time_tolerance is negative ({goal_time} s)")
    return Tolerances(
        path_position,
        path_velocity,
        goal_position,
        goal_velocity,
        goal_time if goal_time > 0.0 else base.goal_time_s,
    )


def _apply(values: FloatArray, index: int, given: float) -> None:
    """A goal's tolerance: > 0 used, 0 the default kept, < 0 none."""
    if given > 0.0:
        values[index] = given
    elif given < 0.0:
        values[index] = np.inf
