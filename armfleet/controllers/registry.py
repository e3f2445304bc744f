"""The controller types an arm can run, by name."""

from __future__ import annotations

from armfleet.controllers.controller import Controller
from armfleet.controllers.joint_state_broadcaster import JointStateBroadcaster
from armfleet.controllers.position_controller import PositionController

#: Every arm runs these, in this order (the broadcaster reads before the controller writes).
CONTROLLER_TYPES: dict[str, type[Controller]] = {
    JointStateBroadcaster.type_name: JointStateBroadcaster,
    PositionController.type_name: PositionController,
}
