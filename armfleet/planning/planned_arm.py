"""What the planner needs of an arm: read its state and limits, and start a planned motion.

The world hands the planner one :class:`PlannedArm` per arm (an
:class:`armfleet.arms.arm_driver.ArmDriver`); the planner never sees the user's handle.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from armfleet.controllers import ControllerManager, PositionController
from armfleet.controllers.jerk_limited_trajectory import SampledMotion
from armfleet.description import ArmDescription
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray, PlannedMotion, Positions
from armfleet.physics.arm_body import ArmBody


class HeldObjects(Protocol):
    """An arm's fingers, as the planner reads them."""

    @property
    def holding(self) -> bool:
        """Whether the fingers hold something (it then moves with the hand)."""
        ...


class PlannedArm(Protocol):
    """An arm the planner plans for and then drives."""

    @property
    def name(self) -> str: ...
    @property
    def joint_names(self) -> tuple[str, ...]: ...
    @property
    def joint_limits(self) -> tuple[FloatArray, FloatArray]: ...
    @property
    def kinematics(self) -> ArmKinematics: ...
    @property
    def description(self) -> ArmDescription: ...
    @property
    def body(self) -> ArmBody: ...
    @property
    def position_controller(self) -> PositionController: ...
    @property
    def controller_manager(self) -> ControllerManager: ...
    @property
    def has_gripper(self) -> bool: ...
    @property
    def gripper(self) -> HeldObjects: ...

    def solve_ik(
        self, pose: Any, frame: str = "world", *, link: str = "tool0", seed: Positions | None = None
    ) -> FloatArray:
        """Arm joint positions that put ``link`` at ``pose`` in ``frame``."""
        ...

    def pose_solver(
        self, pose: Any, frame: str = "world", *, link: str = "tool0"
    ) -> Callable[[FloatArray | None], FloatArray]:
        """The IK of ``link`` at ``pose`` in ``frame``, with the frame looked up now and the
        arm where it is now: safe to call on any thread, reading nothing of the world."""
        ...

    def publish_planned(self, motion: PlannedMotion) -> None:
        """Announce ``motion`` on ``/<arm>/planned_motion``."""

    def follow_motion(self, motion: SampledMotion) -> None:
        """Follow ``motion`` (one row per controller period) from the next step."""

    def tool_position(self, positions: FloatArray) -> FloatArray:
        """World position of tool0 with the arm joints at ``positions`` [m]."""
        ...
