"""Controllers of an arm, split as in ros2_controllers.

Rule: imports :mod:`armfleet.description`, :mod:`armfleet.physics`,
:mod:`armfleet.kinematics`, :mod:`armfleet.runtime` and below; arms are seen through the
``ControlledArm`` protocol (:mod:`~armfleet.controllers.fleet_update`), never the handle.
"""

from armfleet.controllers.controller import ArmContext, Controller, LifecycleState
from armfleet.controllers.controller_manager import ControllerManager
from armfleet.controllers.joint_state_broadcaster import JointStateBroadcaster
from armfleet.controllers.position_controller import PositionController

__all__ = [
    "ArmContext",
    "Controller",
    "ControllerManager",
    "JointStateBroadcaster",
    "LifecycleState",
    "PositionController",
]
