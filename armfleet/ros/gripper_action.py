"""``/<arm>/gripper_controller/gripper_cmd``: ``control_msgs/action/GripperCommand``, as
ros2_controllers' gripper action controller offers it.

``command.position`` is the opening [m] (the angle [rad] for revolute jaws); at the
narrowest opening or below, the gripper grasps (closes until blocked, then presses).
``max_effort`` > 0 is the force per finger, 0 the gripper's default. The goal ends when
the fingers stop: succeeded if they reached the opening or hold something (``stalled``),
aborted otherwise (blocked before the opening with nothing held).
"""

from __future__ import annotations

import logging
import threading
from typing import TYPE_CHECKING, Any

from control_msgs.action import GripperCommand
from rclpy.action.server import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import CallbackGroup

from armfleet.errors import ArmfleetError
from armfleet.ros.deferred_close import GoalCount, close_when_idle

if TYPE_CHECKING:
    from rclpy.action.server import ServerGoalHandle
    from rclpy.node import Node

    from armfleet.arms.arm import Arm
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: An opening within this of the goal counts as reached [m or rad].
REACHED_TOLERANCE = 2e-3
#: Wall time between two looks at the gripper [s].
POLL_S = 0.02


class GripperAction:
    """The gripper action of one arm (only for arms with a gripper)."""

    def __init__(self, node: Node, world: World, arm: Arm, group: CallbackGroup) -> None:
        self._world = world
        self._arm = arm
        self._goals = GoalCount()
        self._closing = False
        self._server = ActionServer(
            node,
            GripperCommand,
            f"/{arm.name}/gripper_controller/gripper_cmd",
            execute_callback=self._execute,
            goal_callback=lambda _request: (
                GoalResponse.REJECT if self._closing else GoalResponse.ACCEPT
            ),
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
            callback_group=group,
        )

    def close(self) -> threading.Thread:
        """Take the action server down once its goals returned (new ones are refused)."""
        self._closing = True
        return close_when_idle(self._goals, self._server.destroy)

    def _execute(self, handle: ServerGoalHandle[Any, Any, Any]) -> Any:
        with self._goals:
            return self._run(handle)

    def _run(self, handle: ServerGoalHandle[Any, Any, Any]) -> Any:
        command = handle.request.command
        gripper = self._arm.gripper
        target = float(command.position)
        force = float(command.max_effort) if command.max_effort > 0 else None

        def start() -> None:
            if target <= gripper.min_width:
                gripper.close(force)
            else:
                gripper.move_to(target, force=force)

        result = GripperCommand.Result()
        try:
            self._world.submit(start).result()
        except ArmfleetError as exc:  # a width or force out of range, the world closing
            logger.warning("%s: gripper_cmd refused: %s", self._arm.name, exc)
            handle.abort()
            return result
        return self._wait(handle, target, result)

    def _wait(self, handle: ServerGoalHandle[Any, Any, Any], target: float, result: Any) -> Any:
        gripper = self._arm.gripper
        stopped = threading.Event()
        while not stopped.wait(POLL_S):
            try:
                state = self._world.submit(
                    lambda: (gripper.is_moving, gripper.width, gripper.force, gripper.holding)
                ).result()
            except ArmfleetError:
                handle.abort()
                return result
            moving, width, force, holding = state
            feedback = GripperCommand.Feedback(
                position=width, effort=force, stalled=holding, reached_goal=False
            )
            if handle.is_cancel_requested:
                self._world.submit(lambda: gripper.move_to(gripper.width))
                handle.canceled()
                return _result(result, width, force, holding, False)
            if moving:
                handle.publish_feedback(feedback)
                continue
            reached = abs(width - target) <= REACHED_TOLERANCE
            if reached or holding:
                handle.succeed()
            else:
                handle.abort()
            return _result(result, width, force, holding, reached)
        return result


def _result(result: Any, width: float, force: float, holding: bool, reached: bool) -> Any:
    result.position, result.effort = float(width), float(force)
    result.stalled, result.reached_goal = bool(holding), bool(reached)
    return result
