"""The controller types an arm can run, by name."""

from __future__ import annotations

from armfleet.controllers.controller import Controller
from armfleet.controllers.gripper_controller import GripperController
from armfleet.controllers.joint_state_broadcaster import JointStateBroadcaster
from armfleet.controllers.position_controller import PositionController

#: An arm runs these, in this order (the broadcaster reads before the controllers write;
#: the gripper writes its fingers' efforts after the position controller). Only arms
#: with fingers run a gripper_controller.
CONTROLLER_TYPES: dict[str, type[Controller]] = {
    JointStateBroadcaster.type_name: JointStateBroadcaster,
    PositionController.type_name: PositionController,
    GripperController.type_name: GripperController,
}
