"""``/<arm>/forward_position_controller/commands``: one position per joint, in the arm's
joint order (``std_msgs/Float64MultiArray``), as ros2_controllers' forward command
controller takes them. armfleet's arm goes there on a jerk-limited motion (its
``move_to``); a refused command is logged and nothing moves."""

from __future__ import annotations

import contextlib
import logging
from typing import TYPE_CHECKING

from rclpy.callback_groups import CallbackGroup
from std_msgs.msg import Float64MultiArray

from armfleet.errors import ArmfleetError

if TYPE_CHECKING:
    from rclpy.node import Node

    from armfleet.arms.arm import Arm
    from armfleet.world import World

logger = logging.getLogger("armfleet")


class ForwardCommand:
    """The command topic of one arm's forward position controller."""

    def __init__(self, node: Node, world: World, arm: Arm, group: CallbackGroup) -> None:
        self._node = node
        self._world = world
        self._arm = arm
        self._subscription = node.create_subscription(
            Float64MultiArray,
            f"/{arm.name}/forward_position_controller/commands",
            self._on_command,
            10,
            callback_group=group,
        )

    def close(self) -> None:
        self._node.destroy_subscription(self._subscription)

    def _on_command(self, message: Float64MultiArray) -> None:
        values = list(message.data)
        arm = self._arm

        def command() -> None:
            try:
                arm.move_to(values)
            except ArmfleetError as exc:
                logger.warning("%s: forward_position_controller command refused: %s", arm.name, exc)

        with contextlib.suppress(ArmfleetError):  # the world is closing
            self._world.submit(command)
