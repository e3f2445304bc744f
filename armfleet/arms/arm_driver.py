"""The side of an arm that the world drives: planned and synchronised motions.

The user's :class:`~armfleet.arms.arm.Arm` offers moves; starting a motion made
elsewhere (a plan, a common duration), announcing it, and the forward kinematics the
planner draws with are plumbing, kept here. The world makes one driver per arm and
hands it to the planner (:class:`~armfleet.planning.planned_arm.PlannedArm`) and to
:func:`~armfleet.motion.synchronised_motion.move_together`.
"""

from __future__ import annotations

from typing import Any

from armfleet import topics
from armfleet.arms.arm import Arm
from armfleet.arms.gripper import Gripper
from armfleet.controllers import ControllerManager, PositionController
from armfleet.controllers.jerk_limited_trajectory import MotionPlan, SampledMotion
from armfleet.description import ArmDescription
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray, JointCommand, PlannedMotion, Positions
from armfleet.physics.arm_body import ArmBody
from armfleet.runtime.bus import Bus


class ArmDriver:
    """Drives ``arm`` for the world: its parts read through the handle (so they raise
    once the arm is removed), commands announced on ``bus`` as the arm's own are."""

    def __init__(self, arm: Arm, bus: Bus) -> None:
        self._arm = arm
        self._bus = bus

    # -- what the planner reads ----------------------------------------------------------
    @property
    def name(self) -> str:
        return self._arm.name

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self._arm.joint_names

    @property
    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        return self._arm.joint_limits

    @property
    def kinematics(self) -> ArmKinematics:
        return self._arm.kinematics

    @property
    def description(self) -> ArmDescription:
        return self._arm.description

    @property
    def body(self) -> ArmBody:
        return self._arm.body

    @property
    def position_controller(self) -> PositionController:
        return self._arm.position_controller

    @property
    def controller_manager(self) -> ControllerManager:
        return self._arm.controller_manager

    @property
    def has_gripper(self) -> bool:
        return self._arm.has_gripper

    @property
    def gripper(self) -> Gripper:
        return self._arm.gripper

    def solve_ik(
        self, pose: Any, frame: str = "world", *, link: str = "tool0", seed: Positions | None = None
    ) -> FloatArray:
        return self._arm.solve_ik(pose, frame, link=link, seed=seed)

    def tool_position(self, positions: FloatArray) -> FloatArray:
        """World position of tool0 with the arm joints at ``positions`` [m]."""
        q = self.body.position.copy()
        q[self.kinematics.arm_indices] = positions
        pose = self._arm.ik.frame_pose(self.description.tool0, q)
        position: FloatArray = pose.translation.copy()
        return position

    # -- what the world starts -------------------------------------------------------------
    def start_plan(self, values: FloatArray, plan: MotionPlan) -> None:
        """Follow ``plan`` to ``values``, made by ``position_controller.plan`` at this step
        (with a common duration, by ``move_together``)."""
        controller = self.position_controller
        self._publish_command(values)  # for the record; the plan replaces its motion
        controller.follow(plan)

    def publish_planned(self, motion: PlannedMotion) -> None:
        """Announce a planned motion on ``/<arm>/planned_motion``."""
        self.position_controller  # noqa: B018 -- raises once the arm is gone
        self._bus.publish(topics.planned_motion(self.name), motion)

    def follow_motion(self, motion: SampledMotion) -> None:
        """Follow ``motion`` (one row per controller period) from the next step, its last
        row published as the command for the record."""
        controller = self.position_controller
        controller.check_samples(motion)
        self._publish_command(motion.position[-1])
        controller.follow_samples(motion)

    def _publish_command(self, values: FloatArray) -> None:
        self._bus.publish(
            topics.position_commands(self.name), JointCommand(tuple(float(v) for v in values))
        )
