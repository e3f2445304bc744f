"""JSON Schemas of the recorded messages, shaped like their ROS 2 counterparts.

Foxglove (and any MCAP tool) reads a channel's JSON messages through its
schema, and recognises the ROS names: ``tf2_msgs/msg/TFMessage`` for the
transforms of the 3D panel, ``sensor_msgs/msg/JointState`` for joint plots.
Messages with no ROS counterpart (``/collisions``, ``/<arm>/status``,
``/bringup``) get a schema derived from their dataclass, named
``armfleet_msgs/msg/<Class>``, so a new message type is recorded without a
change here.

Conventions:
    * A ``stamp`` [s] becomes a ROS ``header`` whose ``stamp`` holds ``sec`` and
      ``nanosec`` (``builtin_interfaces/msg/Time``), plus the same value as
      ``nsec``, the field Foxglove reads in JSON.
    * JSON has no NaN or infinity: such a value (a faulted arm's effort, say) is
      written as ``null``. Every type is a single JSON type, as Foxglove wants.
    * Schemas are self-contained (no ``$ref``).
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


def numbers(description: str = "") -> Schema:
    """An array of numbers (``null`` where a value is not finite)."""
    schema: Schema = {"type": "array", "items": {"type": "number"}}
    if description:
        schema["description"] = description
    return schema


def strings(description: str = "") -> Schema:
    schema: Schema = {"type": "array", "items": {"type": "string"}}
    if description:
        schema["description"] = description
    return schema


def obj(properties: dict[str, Schema], title: str = "", description: str = "") -> Schema:
    """An object with every listed property required."""
    schema: Schema = {"type": "object", "properties": properties, "required": list(properties)}
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


def _trajectory_point(fields: dict[str, str]) -> Schema:
    return obj(
        {name: numbers(text) for name, text in fields.items()},
        title="trajectory_msgs/msg/JointTrajectoryPoint",
    )


CONTROLLER_STATE = MessageSchema(
    "control_msgs/msg/JointTrajectoryControllerState",
    obj(
        {
            "header": HEADER,
            "joint_names": strings("controlled joints"),
            "reference": _trajectory_point(
                {
                    "positions": "Ruckig reference [rad or m]",
                    "velocities": "[rad/s or m/s]",
                    "accelerations": "[rad/s^2 or m/s^2]",
                }
            ),
            "feedback": _trajectory_point(
                {"positions": "measured [rad or m]", "velocities": "measured [rad/s or m/s]"}
            ),
            "error": _trajectory_point(
                {
                    "positions": "tracking error reference - feedback [rad or m]",
                    "velocities": "(empty: not recorded)",
                }
            ),
            "moving": {"type": "boolean", "description": "the reference is still in motion"},
        },
        title="control_msgs/msg/JointTrajectoryControllerState",
        description="position_controller reference and feedback at one update; 'moving' "
        "is armfleet's addition",
    ),
)

STRING = MessageSchema("std_msgs/msg/String", obj({"data": {"type": "string"}}))


# -- armfleet's own messages, derived from their dataclasses -----------------------------
@functools.cache
def dataclass_schema(cls: type) -> MessageSchema:
    """The schema of a dataclass message: fields by type hint, ``stamp`` as a ROS header."""
    return MessageSchema(OWN_PACKAGE + cls.__name__, _object_schema(cls))


def _object_schema(cls: type) -> Schema:
    hints = typing.get_type_hints(cls)
    properties: dict[str, Schema] = {}
    for field in dataclasses.fields(cls):
        if field.name == "stamp":
            properties["header"] = HEADER
        else:
            properties[field.name] = value_schema(hints[field.name])
    return obj(properties, title=OWN_PACKAGE + cls.__name__, description=_summary(cls))


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
        return numbers()
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
