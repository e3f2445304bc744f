"""JSON Schemas of the recorded messages, shaped like their ROS 2 counterparts.

Foxglove (and any MCAP tool) reads a channel's JSON messages through its
schema, and recognises the ROS names: ``tf2_msgs/msg/TFMessage`` for the
transforms of the 3D panel, ``sensor_msgs/msg/JointState`` for joint plots.
Messages with no ROS counterpart (``/collisions``, ``/<arm>/status``,
``/bringup``) get a schema derived from their dataclass, named
``armfleet_msgs/msg/<Class>``, so a new message type is recorded without a
change here. ``/<arm>/planned_motion`` is the exception: its
``armfleet_msgs/msg/PlannedMotion`` is written by hand from ROS parts (a
``trajectory_msgs/msg/JointTrajectory`` and ``geometry_msgs/msg/Point``s), so
ROS tools read its joint path.

Conventions:
    * A ``stamp`` [s] becomes a ROS ``header`` whose ``stamp`` holds ``sec`` and
      ``nanosec`` (``builtin_interfaces/msg/Time``), plus the same value as
      ``nsec``, the field Foxglove reads in JSON.
    * Every field has a single JSON type: Foxglove turns a JSON Schema into
      message fields by its ``type`` and refuses a list such as
      ``["number", "null"]`` (or a field without one), which would hide the whole
      channel. Schemas are self-contained (no ``$ref``).
    * Non-finite numbers (a faulted arm's torques, a physics blow-up, a refused
      NaN target) are **never written**, because JSON has no NaN or infinity and
      writing ``null`` or ``"NaN"`` in a ``number`` field would break either the
      schema or Foxglove. Instead, as ROS itself marks data that is not
      available: an array of numbers holding one is written empty (ROS's
      ``JointState`` and ``JointTrajectoryPoint`` define an empty array as "not
      available"); a transform holding one is left out of its ``TFMessage``; a
      field of armfleet's own messages holding one is left out of its object, and
      those schemas require only the fields that cannot hold one. Readers turn
      what is missing back into NaN (:func:`armfleet.recording.encode.numbers_or_nan`).
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import json
import typing
from dataclasses import dataclass
from typing import Any

import numpy as np

JSON_SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"
#: Prefix of the schemas of armfleet's own messages.
OWN_PACKAGE = "armfleet_msgs/msg/"

Schema = dict[str, Any]


@dataclass(frozen=True)
class MessageSchema:
    """A named JSON Schema, as an MCAP schema record holds it.

    Attributes:
        name: ROS-style type name, e.g. ``sensor_msgs/msg/JointState``.
        schema: the JSON Schema.
    """

    name: str
    schema: Schema

    @property
    def data(self) -> bytes:
        """The schema as UTF-8 JSON text."""
        return json.dumps({"$schema": JSON_SCHEMA_DIALECT, **self.schema}, indent=1).encode()


# -- building blocks ---------------------------------------------------------------------
def number(description: str = "") -> Schema:
    return {"type": "number", **({"description": description} if description else {})}


#: How an array of numbers says it is not available.
EMPTY_IF_NOT_FINITE = "empty when a value is not finite (not available, as in ROS)"


def numbers(description: str = "") -> Schema:
    """An array of numbers (written empty when any value is not finite)."""
    text = f"{description}; {EMPTY_IF_NOT_FINITE}" if description else EMPTY_IF_NOT_FINITE
    return {"type": "array", "items": {"type": "number"}, "description": text}


def strings(description: str = "") -> Schema:
    schema: Schema = {"type": "array", "items": {"type": "string"}}
    if description:
        schema["description"] = description
    return schema


def obj(
    properties: dict[str, Schema],
    title: str = "",
    description: str = "",
    optional: tuple[str, ...] = (),
) -> Schema:
    """An object with every listed property required but those ``optional``."""
    required = [name for name in properties if name not in optional]
    schema: Schema = {"type": "object", "properties": properties, "required": required}
    if title:
        schema["title"] = title
    if description:
        schema["description"] = description
    return schema


TIME = obj(
    {
        "sec": {"type": "integer", "minimum": 0},
        "nanosec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        "nsec": {
            "type": "integer",
            "minimum": 0,
            "maximum": 999_999_999,
            "description": "same as nanosec (the name Foxglove reads in JSON)",
        },
    },
    title="builtin_interfaces/msg/Time",
    description="simulated time",
)
HEADER = obj({"stamp": TIME, "frame_id": {"type": "string"}}, title="std_msgs/msg/Header")
VECTOR3 = obj({"x": number(), "y": number(), "z": number()}, title="geometry_msgs/msg/Vector3")
QUATERNION = obj(
    {"x": number(), "y": number(), "z": number(), "w": number()},
    title="geometry_msgs/msg/Quaternion",
)

# -- ROS messages ------------------------------------------------------------------------
JOINT_STATE = MessageSchema(
    "sensor_msgs/msg/JointState",
    obj(
        {
            "header": HEADER,
            "name": strings("prefixed joint names"),
            "position": numbers("[rad or m]"),
            "velocity": numbers("[rad/s or m/s]"),
            "effort": numbers("commanded effort [Nm or N]"),
        },
        title="sensor_msgs/msg/JointState",
    ),
)

TRANSFORM_STAMPED = obj(
    {
        "header": HEADER,
        "child_frame_id": {"type": "string"},
        "transform": obj(
            {"translation": VECTOR3, "rotation": QUATERNION}, title="geometry_msgs/msg/Transform"
        ),
    },
    title="geometry_msgs/msg/TransformStamped",
    description="pose of child_frame_id in header.frame_id (translation in [m])",
)
TF_MESSAGE = MessageSchema(
    "tf2_msgs/msg/TFMessage",
    obj(
        {"transforms": {"type": "array", "items": TRANSFORM_STAMPED}},
        title="tf2_msgs/msg/TFMessage",
    ),
)

FLOAT64_MULTI_ARRAY = MessageSchema(
    "std_msgs/msg/Float64MultiArray",
    obj(
        {
            "layout": obj(
                {
                    "dim": {
                        "type": "array",
                        "items": obj(
                            {
                                "label": {"type": "string"},
                                "size": {"type": "integer"},
                                "stride": {"type": "integer"},
                            }
                        ),
                    },
                    "data_offset": {"type": "integer"},
                },
                title="std_msgs/msg/MultiArrayLayout",
            ),
            "data": numbers("target positions in the arm's joint order [rad or m]"),
        },
        title="std_msgs/msg/Float64MultiArray",
    ),
)


DURATION = obj(
    {"sec": {"type": "integer"}, "nanosec": {"type": "integer", "minimum": 0}},
    title="builtin_interfaces/msg/Duration",
)
TRANSFORM = obj(
    {"translation": VECTOR3, "rotation": QUATERNION}, title="geometry_msgs/msg/Transform"
)
TWIST = obj({"linear": VECTOR3, "angular": VECTOR3}, title="geometry_msgs/msg/Twist")


def trajectory_point(description: str, **fields: str) -> Schema:
    """A ``trajectory_msgs/msg/JointTrajectoryPoint``; arrays not in ``fields`` are empty."""
    arrays = ("positions", "velocities", "accelerations", "effort")
    return obj(
        {
            **{name: numbers(fields.get(name, "empty: not recorded")) for name in arrays},
            "time_from_start": {**DURATION, "description": "0: not tracked"},
        },
        title="trajectory_msgs/msg/JointTrajectoryPoint",
        description=description,
    )


def _multi_dof_point(description: str) -> Schema:
    return obj(
        {
            "transforms": {"type": "array", "items": TRANSFORM},
            "velocities": {"type": "array", "items": TWIST},
            "accelerations": {"type": "array", "items": TWIST},
            "time_from_start": DURATION,
        },
        title="trajectory_msgs/msg/MultiDOFJointTrajectoryPoint",
        description=description,
    )


_REFERENCE = trajectory_point(
    "the set point: the Ruckig reference at the stamp",
    positions="[rad or m]",
    velocities="[rad/s or m/s]",
    accelerations="[rad/s^2 or m/s^2]",
)
_FEEDBACK = trajectory_point(
    "the measured state at the stamp",
    positions="measured [rad or m]",
    velocities="measured [rad/s or m/s]",
)
_NO_MULTI_DOF = "empty: armfleet's arms have no multi-DOF joints"

#: ``control_msgs/msg/JointTrajectoryControllerState`` as ROS 2 Humble defines it: Jazzy's
#: fields plus the deprecated ``desired`` and ``actual`` (copies of ``reference`` and
#: ``feedback``, as Humble's joint_trajectory_controller fills them), so a reader of either
#: release finds every field it knows. (Kilted's ``speed_scaling_factor`` is not written.)
CONTROLLER_STATE = MessageSchema(
    "control_msgs/msg/JointTrajectoryControllerState",
    obj(
        {
            "header": HEADER,
            "joint_names": strings("controlled joints"),
            "reference": _REFERENCE,
            "feedback": _FEEDBACK,
            "error": trajectory_point(
                "reference - feedback",
                positions="tracking error [rad or m]",
                velocities="velocity error [rad/s or m/s]",
            ),
            "output": trajectory_point(
                "the controller's output: empty here (its torques are the effort of "
                "/<arm>/joint_states)"
            ),
            "desired": {**_REFERENCE, "description": "deprecated copy of reference"},
            "actual": {**_FEEDBACK, "description": "deprecated copy of feedback"},
            "multi_dof_joint_names": strings(_NO_MULTI_DOF),
            **{
                f"multi_dof_{part}": _multi_dof_point(_NO_MULTI_DOF)
                for part in ("reference", "feedback", "error", "output", "desired", "actual")
            },
        },
        title="control_msgs/msg/JointTrajectoryControllerState",
        description="position_controller reference and feedback at one update",
    ),
)

STRING = MessageSchema("std_msgs/msg/String", obj({"data": {"type": "string"}}))

# -- a planned motion: a ROS JointTrajectory plus the tool path drawn for it -------------
POINT = obj({"x": number(), "y": number(), "z": number()}, title="geometry_msgs/msg/Point")
_WAYPOINT = obj(
    {
        "positions": numbers("[rad or m]"),
        **{name: numbers("empty: not planned") for name in ("velocities", "accelerations")},
        "effort": numbers("empty: not planned"),
        "time_from_start": {**DURATION, "description": "time after header.stamp"},
    },
    title="trajectory_msgs/msg/JointTrajectoryPoint",
    description="a waypoint; the joints move in a straight line between two",
)
JOINT_TRAJECTORY = obj(
    {
        "header": {**HEADER, "description": "stamp: when the motion starts (as in ROS)"},
        "joint_names": strings("the arm's controlled joints"),
        "points": {
            "type": "array",
            "items": _WAYPOINT,
            "description": "a waypoint whose time is not finite is left out",
        },
    },
    title="trajectory_msgs/msg/JointTrajectory",
)
#: ``/<arm>/planned_motion`` (:class:`armfleet.messages.PlannedMotion`). Not a
#: ``moveit_msgs/msg/DisplayTrajectory``: that one has no place for the tool path and
#: holds a robot state this message does not have; its joint path is a ROS
#: ``trajectory_msgs/msg/JointTrajectory`` and its tool path ``geometry_msgs/msg/Point``s.
PLANNED_MOTION = MessageSchema(
    OWN_PACKAGE + "PlannedMotion",
    obj(
        {
            "header": {
                **HEADER,
                "description": "stamp: when the motion starts; frame_id: that of tool_path",
            },
            "trajectory": JOINT_TRAJECTORY,
            "tool_path": {
                "type": "array",
                "items": POINT,
                "description": (
                    "world positions [m] of the arm's tool0 along the motion, start to goal; "
                    f"{EMPTY_IF_NOT_FINITE}"
                ),
            },
        },
        title=OWN_PACKAGE + "PlannedMotion",
        description="a collision-free plan starting on an arm: the path it will follow",
    ),
)


# -- armfleet's own messages, derived from their dataclasses -----------------------------
@functools.cache
def dataclass_schema(cls: type) -> MessageSchema:
    """The schema of a dataclass message: fields by type hint, ``stamp`` as a ROS header."""
    return MessageSchema(OWN_PACKAGE + cls.__name__, _object_schema(cls))


def _object_schema(cls: type) -> Schema:
    """Fields by type hint; those that can hold a non-finite number are optional."""
    hints = typing.get_type_hints(cls)
    properties: dict[str, Schema] = {}
    optional: list[str] = []
    for field in dataclasses.fields(cls):
        if field.name == "stamp":
            properties["header"] = HEADER
            continue
        schema = value_schema(hints[field.name])
        if _holds_numbers(schema):
            text = schema.get("description", "")
            note = "left out when not finite"
            schema = {**schema, "description": f"{text}; {note}" if text else note}
            optional.append(field.name)
        properties[field.name] = schema
    return obj(
        properties,
        title=OWN_PACKAGE + cls.__name__,
        description=_summary(cls),
        optional=tuple(optional),
    )


def _holds_numbers(schema: Schema) -> bool:
    """Whether a value of ``schema`` is a number or an array of them (may be non-finite)."""
    if schema.get("type") == "number":
        return True
    return schema.get("type") == "array" and _holds_numbers(schema.get("items", {}))


def value_schema(hint: Any) -> Schema:
    """The schema of a value of type ``hint`` as :mod:`armfleet.recording.encode` writes it."""
    origin = typing.get_origin(hint)
    if hint is bool:
        return {"type": "boolean"}
    if hint is int:
        return {"type": "integer"}
    if hint is float:
        return {"type": "number"}
    if hint is str:
        return {"type": "string"}
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return {"type": "string", "enum": [member.value for member in hint]}
    if hint is np.ndarray or origin is np.ndarray:
        return {"type": "array", "items": {"type": "number"}}
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return _object_schema(hint)
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return {"type": "array", "items": value_schema(args[0])}
        if len(set(args)) == 1:
            return {
                "type": "array",
                "items": value_schema(args[0]),
                "minItems": len(args),
                "maxItems": len(args),
            }
    return {"description": f"any JSON value ({hint})"}


def _summary(cls: type) -> str:
    doc = (cls.__doc__ or "").strip()
    return doc.split("\n\n")[0].replace("\n", " ")
