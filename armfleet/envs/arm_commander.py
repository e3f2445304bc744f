"""Turns one arm's checked action into commands: a joint target for its position
controller (a new jerk-limited Ruckig motion from the moving reference) and, on a change,
an open or close of its gripper.

Deltas are added to the previous *target*, not to the measured state, so that a zero
action keeps the arm going where it was sent; at reset the targets are where the arm is.
A ``tool_servo`` action is the exception: it moves tool0 from where it *is* (measured),
its orientation held at the episode's start, so the target never runs ahead of the arm
by more than one action and a zero action stops the arm where it is.
A target the arm would refuse (a tool pose no configuration reaches, a motion that would
overshoot a joint limit, an arm in protective stop) is not sent: the previous target
stays, and :meth:`ArmCommander.apply` returns why.
"""

from __future__ import annotations

import numpy as np

from armfleet.arms.arm import Arm
from armfleet.envs.actions import GRIPPER, GRIPPER_CLOSE_ABOVE, ActionKind
from armfleet.envs.poses import moved
from armfleet.errors import (
    ArmFault,
    MotionLimitError,
    ProtectiveStopError,
    UnreachablePose,
)
from armfleet.messages import FloatArray
from armfleet.world import World


class ArmCommander:
    """The command state of one arm in one episode.

    Args:
        world: the episode's world.
        arm: the arm.
        kind: what its actions command.
    """

    def __init__(self, world: World, arm: Arm, kind: ActionKind) -> None:
        self._world = world
        self._arm = arm
        self._kind = kind
        self._lower, self._upper = arm.joint_limits
        self._target = arm.positions
        self._tool_target = world.tf.world_pose(arm.description.tool0)
        #: Whether the fingers were last told to close; None before the first command.
        self._closed: bool | None = None

    @property
    def target(self) -> FloatArray:
        """The arm's joint target [rad] (a copy)."""
        return self._target.copy()

    @property
    def tool_target(self) -> FloatArray:
        """The 4x4 world pose tool0 is sent to (tool-delta actions; a copy)."""
        return self._tool_target.copy()

    def rebase(self) -> None:
        """Take the arm's measured joints and tool0 as the targets (after a stop)."""
        self._target = self._arm.positions
        self._tool_target = self._world.tf.world_pose(self._arm.description.tool0)

    def apply(self, action: dict[str, FloatArray]) -> str:
        """Send ``action`` (checked and clipped); returns "" or why the arm target was
        not sent (the gripper's command is sent either way)."""
        refused = self._send_arm(action[self._kind.value])
        if GRIPPER in action:
            self._send_gripper(bool(action[GRIPPER][0] > GRIPPER_CLOSE_ABOVE))
        return refused

    def _send_arm(self, value: FloatArray) -> str:
        arm = self._arm
        tool_target = self._tool_target
        if self._kind is ActionKind.JOINT_POSITIONS:
            target = np.clip(value, self._lower, self._upper)
        elif self._kind is ActionKind.JOINT_DELTAS:
            target = np.clip(self._target + value, self._lower, self._upper)
        elif self._kind is ActionKind.TOOL_SERVO:
            tool_target = self._tool_target.copy()  # the start's orientation
            tool_target[:3, 3] = self._world.tf.world_pose(arm.description.tool0)[:3, 3] + value
            try:
                target = arm.solve_ik(tool_target, seed=arm.positions)
            except UnreachablePose as exc:
                return str(exc)
        else:
            if not value.any():
                return ""  # keep the motion there is (no IK needed)
            tool_target = moved(self._tool_target, value)
            try:
                target = arm.solve_ik(tool_target, seed=self._target)
            except UnreachablePose as exc:
                return str(exc)
        if np.array_equal(target, self._target):
            return ""  # the same target: the motion goes on as planned
        try:
            arm.move_to(target)
        except (MotionLimitError, ProtectiveStopError, ArmFault) as exc:
            return str(exc)
        self._target = target
        self._tool_target = tool_target
        return ""

    def _send_gripper(self, close: bool) -> None:
        if close == self._closed:
            return
        self._closed = close
        if close:
            self._arm.gripper.close()
        else:
            self._arm.gripper.open()
