"""Every topic armfleet publishes: its name and the message it carries.

World topics have one name; an arm's topics live in its namespace ``/<arm>`` and are
made by the functions below, so no module spells a topic by hand. The message types
are in :mod:`armfleet.messages`; :data:`WORLD_TOPICS` and :func:`arm_topics` pair each
name with its type (the recording's schemas and the live API's ``topic list`` read them).
"""

from __future__ import annotations

from armfleet import messages

#: Each arm's bring-up stages (:class:`~armfleet.messages.BringupEvent`).
BRINGUP = "/bringup"
#: Every arm's and object's moving frames (:class:`~armfleet.messages.TFMessage`).
TF = "/tf"
#: Fixed frames, latched (:class:`~armfleet.messages.TFMessage`).
TF_STATIC = "/tf_static"
#: New and ended contacts (:class:`~armfleet.messages.CollisionReport`).
COLLISIONS = "/collisions"

#: The scene's objects as Foxglove draws them (``foxglove.SceneUpdate``; Foxglove only).
SCENE_OBJECTS = "/scene_objects"

#: World topic -> message type.
WORLD_TOPICS: dict[str, type] = {
    BRINGUP: messages.BringupEvent,
    TF: messages.TFMessage,
    TF_STATIC: messages.TFMessage,
    COLLISIONS: messages.CollisionReport,
}


def namespace(arm: str) -> str:
    """The arm's namespace, ``/<arm>``: every topic below is in it."""
    return f"/{arm}"


def joint_states(arm: str) -> str:
    """Measured joint states (:class:`~armfleet.messages.JointState`)."""
    return f"/{arm}/joint_states"


def position_commands(arm: str) -> str:
    """Joint targets given to the position controller (:class:`~armfleet.messages.JointCommand`)."""
    return f"/{arm}/position_controller/commands"


def position_controller_state(arm: str) -> str:
    """Reference, error and torque (:class:`~armfleet.messages.ControllerState`)."""
    return f"/{arm}/position_controller/state"


def gripper_commands(arm: str) -> str:
    """Gripper commands (:class:`~armfleet.messages.GripperCommand`)."""
    return f"/{arm}/gripper_controller/commands"


def planned_motion(arm: str) -> str:
    """A planned motion as it starts (:class:`~armfleet.messages.PlannedMotion`)."""
    return f"/{arm}/planned_motion"


def status(arm: str) -> str:
    """Mode, fault and stop count, ten times a second (:class:`~armfleet.messages.ArmStatus`)."""
    return f"/{arm}/status"


def robot_description(arm: str) -> str:
    """The arm's expanded URDF, as Foxglove and the recordings carry it (text)."""
    return f"/{arm}/robot_description"
