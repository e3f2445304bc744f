"""Controllers of an arm, split as in ros2_controllers.

Rule: imports :mod:`armfleet.description`, :mod:`armfleet.physics`,
:mod:`armfleet.kinematics`, :mod:`armfleet.runtime` and below; arms are seen through the
``ControlledArm`` protocol (:mod:`~armfleet.controllers.fleet_update`), never the handle.
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.controllers.controller import ArmContext, Controller, LifecycleState
    from armfleet.controllers.controller_manager import ControllerManager
    from armfleet.controllers.joint_state_broadcaster import JointStateBroadcaster
    from armfleet.controllers.position_controller import PositionController

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ArmContext": "armfleet.controllers.controller",
        "Controller": "armfleet.controllers.controller",
        "LifecycleState": "armfleet.controllers.controller",
        "ControllerManager": "armfleet.controllers.controller_manager",
        "JointStateBroadcaster": "armfleet.controllers.joint_state_broadcaster",
        "PositionController": "armfleet.controllers.position_controller",
    },
)

__all__ = [
    "ArmContext",
    "Controller",
    "ControllerManager",
    "JointStateBroadcaster",
    "LifecycleState",
    "PositionController",
]
