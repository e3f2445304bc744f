"""Several arms that start on the same step and finish at the same instant.

Each arm's motion is first planned alone (Ruckig, time-optimal within its own
limits); the longest of those durations becomes the common one, and every arm
is planned again with Ruckig's ``minimum_duration`` set to it. Ruckig keeps
each arm's joints finishing together and within their limits; when it has to
take a little longer than asked (a duration some joint cannot match within
its jerk limit), the longest duration is taken again until all agree.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol

from armfleet.controllers import ControllerManager, PositionController
from armfleet.controllers.jerk_limited_trajectory import MotionPlan, TrajectoryError
from armfleet.errors import ArmFault, ArmfleetError
from armfleet.kinematics.inverse_kinematics import is_pose
from armfleet.messages import FloatArray
from armfleet.motion.pose_goal import PoseGoal


class SynchronisedArm(Protocol):
    """An arm as a synchronised motion drives it (the world's
    :class:`~armfleet.arms.arm_driver.ArmDriver`)."""

    @property
    def controller_manager(self) -> ControllerManager: ...
    @property
    def position_controller(self) -> PositionController: ...

    def solve_ik(self, pose: Any, frame: str = "world", *, link: str = "tool0") -> FloatArray:
        """SynchronisedArm joint positions that put ``link`` at ``pose`` in ``frame``."""
        ...

    def check_self_contact(self, plan: MotionPlan) -> None:
        """Raise ``SelfContactError`` if ``plan`` (made at this step) would bring the arm
        within the clearance of itself (see :mod:`armfleet.arms.self_contact`)."""

    def start_plan(self, values: FloatArray, plan: MotionPlan) -> None:
        """Follow ``plan`` (made at this step) to ``values``."""


#: Durations that agree to this are the same instant [s].
SYNC_TOLERANCE_S = 1e-9
_ROUNDS = 10


def joint_target(arm: SynchronisedArm, target: Any) -> FloatArray:
    """``target`` as arm joint positions: joint positions as they are, a 4x4 pose
    (or ``pinocchio.SE3``) of tool0 in the world, or a :class:`PoseGoal`, through IK."""
    if isinstance(target, PoseGoal):
        return arm.solve_ik(target.pose, target.frame, link=target.link)
    if is_pose(target):
        return arm.solve_ik(target)
    return arm.position_controller.validate(target)


def move_together(arms: Mapping[str, tuple[SynchronisedArm, Any]]) -> float:
    """Plan every arm, then start them all; returns the common duration [s].

    Args:
        arms: per arm name, the arm and its target (see :func:`joint_target`).

    Each arm's motion, as planned with the common duration, is checked against touching
    the arm itself before any arm starts.

    Raises:
        ArmfleetError: any arm's target or state is bad, or its motion would touch the
            arm itself (``SelfContactError``); then no arm moves.
    """
    if not arms:
        raise ArmfleetError("move_together needs at least one arm: {'<arm>': target, ...}")
    targets: dict[str, tuple[SynchronisedArm, FloatArray]] = {}
    for name, (arm, target) in arms.items():
        if arm.controller_manager.fault is not None:
            raise ArmFault(name, arm.controller_manager.fault)
        targets[name] = (arm, joint_target(arm, target))
    plans = {name: arm.position_controller.plan(values) for name, (arm, values) in targets.items()}
    duration = max(plan.duration for plan in plans.values())
    for _ in range(_ROUNDS):
        plans = _plan_all(targets, duration)
        durations = [plan.duration for plan in plans.values()]
        if max(durations) - min(durations) <= SYNC_TOLERANCE_S:
            break
        duration = max(durations)
    else:
        raise TrajectoryError(
            f"Ruckig found no common duration for {', '.join(arms)}; move them one by one"
        )
    for name, (arm, _) in targets.items():
        arm.check_self_contact(plans[name])
    for name, (arm, values) in targets.items():
        arm.start_plan(values, plans[name])
    return max(plan.duration for plan in plans.values())


def _plan_all(
    targets: Mapping[str, tuple[SynchronisedArm, FloatArray]], duration_s: float
) -> dict[str, MotionPlan]:
    return {
        name: arm.position_controller.plan(values, duration_s)
        for name, (arm, values) in targets.items()
    }
