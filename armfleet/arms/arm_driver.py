"""The side of an arm that the world drives: planned and synchronised motions.

The user's :class:`~armfleet.arms.arm.Arm` offers moves; starting a motion made
elsewhere (a plan, a common duration), announcing it, and the forward kinematics the
planner draws with are plumbing, kept here. The world makes one driver per arm and
hands it to the planner (:class:`~armfleet.planning.planned_arm.PlannedArm`) and to
:func:`~armfleet.motion.synchronised_motion.move_together`.

The planner may solve a pose goal on a worker thread while the world steps: it asks the
driver, on the stepping thread, for a :meth:`ArmDriver.pose_solver`, which looks the goal's
frame up then and solves later with IK data of its own, reading nothing of the world.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from armfleet import topics
from armfleet.arms.arm import Arm
from armfleet.arms.gripper import Gripper
from armfleet.controllers import ControllerManager, PositionController
from armfleet.controllers.jerk_limited_trajectory import MotionPlan, SampledMotion
from armfleet.description import ArmDescription
from armfleet.errors import UnreachablePose
from armfleet.kinematics import ArmKinematics
from armfleet.kinematics.inverse_kinematics import InverseKinematics, link_frame, world_goal
from armfleet.messages import FloatArray, JointCommand, PlannedMotion, Positions
from armfleet.physics.arm_body import ArmBody
from armfleet.runtime.bus import Bus


class ArmDriver:
    """Drives ``arm`` for the world: its parts read through the handle (so they raise
    once the arm is removed), commands announced on ``bus`` as the arm's own are.

    Args:
        arm: the arm.
        bus: the world's bus.
        frame_pose: the world pose of any frame of the world (the TF tree's), for pose goals.
    """

    def __init__(self, arm: Arm, bus: Bus, frame_pose: Callable[[str], FloatArray]) -> None:
        self._arm = arm
        self._bus = bus
        self._frame_pose = frame_pose

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

    def pose_solver(
        self, pose: Any, frame: str = "world", *, link: str = "tool0"
    ) -> Callable[[FloatArray | None], FloatArray]:
        """The IK of ``link`` at ``pose`` in ``frame`` (as :meth:`solve_ik`), its frame looked
        up and the arm's position read now; the solve runs on any thread, later, with IK
        data of its own.

        Raises:
            TargetPoseError, UnknownFrame: now, as :meth:`solve_ik` raises them.
        """
        arm = self._arm
        kinematics = arm.kinematics
        frame_name = link_frame(arm.name, kinematics, arm.description.prefix, link)
        goal = world_goal(pose, frame, self._frame_pose)
        here = self.body.position.copy()
        indices = kinematics.arm_indices
        ik = InverseKinematics(kinematics)
        name = arm.name

        def solve(seed: FloatArray | None) -> FloatArray:
            start = here.copy()
            if seed is not None:
                start[indices] = seed
            solution = ik.solve(frame_name, goal, start)
            if not solution.converged:
                raise UnreachablePose(
                    name, link, solution.position_error_m, solution.rotation_error_rad
                )
            positions: FloatArray = solution.positions[indices].copy()
            return positions

        return solve

    def tool_position(self, positions: FloatArray) -> FloatArray:
        """World position of tool0 with the arm joints at ``positions`` [m]."""
        q = self.body.position.copy()
        q[self.kinematics.arm_indices] = positions
        pose = self._arm.ik.frame_pose(self.description.tool0, q)
        position: FloatArray = pose.translation.copy()
        return position

    # -- what the world starts -------------------------------------------------------------
    def check_self_contact(self, plan: MotionPlan) -> None:
        """Raise :class:`~armfleet.errors.SelfContactError` if ``plan`` (made by
        ``position_controller.plan`` at this step) would bring the arm within 1 mm of itself."""
        self._arm.check_self_contact(plan)

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
