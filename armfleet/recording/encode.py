"""Bus messages to the JSON of :mod:`armfleet.recording.schemas`, fast enough for 1 kHz topics.

A recorder encodes every joint state, controller state and ``/tf`` message of
every arm at the physics rate, so the encoders of those three fill a per-topic
template (built once per set of joint or frame names) with all the numbers of
a message in one ``%`` operation. Numbers are written with 17 significant
digits: reading them back gives the very same doubles. A message holding a
non-finite number takes the slow path, which does not write it: see the
conventions in :mod:`armfleet.recording.schemas` (an array holding one is written
empty, a transform holding one is left out, an own message's field holding one is
left out) and :func:`numbers_or_nan` for reading such a message back.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np

from armfleet.messages import (
    ControllerState,
    JointCommand,
    JointState,
    PlannedMotion,
    TFMessage,
)
from armfleet.recording.schemas import (
    CONTROLLER_STATE,
    FLOAT64_MULTI_ARRAY,
    JOINT_STATE,
    OWN_PACKAGE,
    PLANNED_MOTION,
    STRING,
    TF_MESSAGE,
    MessageSchema,
    dataclass_schema,
)

NS_PER_S = 1_000_000_000
#: printf format of a number: 17 significant digits round-trip every double.
NUMBER = "%.17g"
_HEADER = '"header":{"stamp":{"sec":%d,"nanosec":%d,"nsec":%d},"frame_id":""}'


class MessageEncoder(Protocol):
    """Turns messages of one type into JSON bytes matching :attr:`schema`."""

    @property
    def schema(self) -> MessageSchema: ...

    def __call__(self, message: Any) -> bytes: ...


def stamp_ns(seconds: float) -> int:
    """Simulated time [s] as integer nanoseconds (MCAP log times, ROS stamps)."""
    return round(seconds * NS_PER_S)


def _stamp(seconds: float) -> tuple[int, int]:
    sec, nanosec = divmod(round(seconds * NS_PER_S), NS_PER_S)
    return sec, nanosec


def header(seconds: float, frame_id: str = "") -> dict[str, Any]:
    """A ROS ``std_msgs/msg/Header`` as JSON values."""
    sec, nanosec = _stamp(seconds)
    return {"stamp": {"sec": sec, "nanosec": nanosec, "nsec": nanosec}, "frame_id": frame_id}


def dumps(value: Any) -> bytes:
    """Compact JSON (no NaN: callers pass finite numbers only)."""
    return json.dumps(value, separators=(",", ":"), allow_nan=False).encode()


def finite_or_empty(values: Any) -> list[float]:
    """Numbers as a list; empty ("not available", as in ROS) if any is not finite."""
    flat: list[float] = np.asarray(values, dtype=float).ravel().tolist()
    return flat if all(math.isfinite(v) for v in flat) else []


def numbers_or_nan(values: Any, count: int) -> tuple[float, ...]:
    """``count`` numbers read back from a recorded array: NaN for each if the array was
    written empty or is missing (a value was not finite), and for a ``null`` (recordings
    made before non-finite values were left out)."""
    if not values:
        return (math.nan,) * count
    return tuple(math.nan if v is None else float(v) for v in values)


def _literal(value: Any) -> str:
    """JSON text of ``value``, safe inside a ``%`` template."""
    return json.dumps(value, separators=(",", ":")).replace("%", "%%")


def _numbers(count: int) -> str:
    return "[" + ",".join([NUMBER] * count) + "]"


# -- sensor_msgs/msg/JointState ----------------------------------------------------------
class JointStateEncoder:
    """``JointState`` -> ``sensor_msgs/msg/JointState``."""

    schema = JOINT_STATE

    def __init__(self) -> None:
        self._templates: dict[tuple[str, ...], str] = {}

    def __call__(self, message: JointState) -> bytes:
        n = len(message.name)
        values = np.concatenate((message.position, message.velocity, message.effort))
        if values.shape != (3 * n,) or not np.isfinite(values).all():
            return dumps(
                {
                    "header": header(message.stamp),
                    "name": list(message.name),
                    "position": finite_or_empty(message.position),
                    "velocity": finite_or_empty(message.velocity),
                    "effort": finite_or_empty(message.effort),
                }
            )
        template = self._templates.get(message.name)
        if template is None:
            array = _numbers(n)
            template = (
                f'{{{_HEADER},"name":{_literal(list(message.name))},"position":{array},'
                f'"velocity":{array},"effort":{array}}}'
            )
            self._templates[message.name] = template
        sec, nanosec = _stamp(message.stamp)
        return (template % (sec, nanosec, nanosec, *values.tolist())).encode()


# -- control_msgs/msg/JointTrajectoryControllerState -------------------------------------
_NO_TIME = '"time_from_start":{"sec":0,"nanosec":0}'
_EMPTY_POINT = '{"positions":[],"velocities":[],"accelerations":[],"effort":[],' + _NO_TIME + "}"
_EMPTY_MULTI_DOF = '{"transforms":[],"velocities":[],"accelerations":[],' + _NO_TIME + "}"
_MULTI_DOF = ",".join(
    f'"multi_dof_{part}":{_EMPTY_MULTI_DOF}'
    for part in ("reference", "feedback", "error", "output", "desired", "actual")
)


def _point(positions: str, velocities: str, accelerations: str) -> str:
    """A JointTrajectoryPoint with the given JSON arrays and no effort."""
    return (
        f'{{"positions":{positions},"velocities":{velocities},'
        f'"accelerations":{accelerations},"effort":[],{_NO_TIME}}}'
    )


class ControllerStateEncoder:
    """``ControllerState`` -> ``control_msgs/msg/JointTrajectoryControllerState``, every
    field of the ROS 2 Humble message (see :data:`~armfleet.recording.schemas.CONTROLLER_STATE`).

    ``error`` is reference - feedback (positions and velocities); ``desired`` and
    ``actual`` repeat ``reference`` and ``feedback``; ``output`` and the multi-DOF
    points are empty.
    """

    schema = CONTROLLER_STATE

    def __init__(self) -> None:
        self._templates: dict[tuple[str, ...], tuple[str, str, str]] = {}

    def __call__(self, message: ControllerState) -> bytes:
        n = len(message.name)
        reference, position = message.reference_position, message.position
        ref_velocity, velocity = message.reference_velocity, message.velocity
        values = np.concatenate(
            (
                reference,
                ref_velocity,
                message.reference_acceleration,
                position,
                velocity,
                reference - position,
                ref_velocity - velocity,
            )
        )
        if values.shape != (7 * n,) or not np.isfinite(values).all():
            return self._slow(message)
        templates = self._templates.get(message.name)
        if templates is None:
            array = _numbers(n)
            templates = (
                _point(array, array, array),
                _point(array, array, "[]"),
                f'{{{_HEADER},"joint_names":{_literal(list(message.name))},',
            )
            self._templates[message.name] = templates
        three, two, head = templates
        numbers = values.tolist()
        sec, nanosec = _stamp(message.stamp)
        ref = three % tuple(numbers[: 3 * n])
        feedback = two % tuple(numbers[3 * n : 5 * n])
        error = two % tuple(numbers[5 * n :])
        return self._assemble(head % (sec, nanosec, nanosec), ref, feedback, error)

    @staticmethod
    def _assemble(head: str, reference: str, feedback: str, error: str) -> bytes:
        return (
            f'{head}"reference":{reference},"feedback":{feedback},"error":{error},'
            f'"output":{_EMPTY_POINT},"desired":{reference},"actual":{feedback},'
            f'"multi_dof_joint_names":[],{_MULTI_DOF}}}'
        ).encode()

    def _slow(self, message: ControllerState) -> bytes:
        """The same message when a value is not finite: each array holding one is empty."""

        def point(*arrays: Any) -> str:
            texts = [dumps(finite_or_empty(a)).decode() for a in arrays]
            return _point(*texts, *(["[]"] * (3 - len(texts))))

        head = dumps({"header": header(message.stamp), "joint_names": list(message.name)})
        reference = point(
            message.reference_position, message.reference_velocity, message.reference_acceleration
        )
        feedback = point(message.position, message.velocity)
        error = point(
            np.subtract(message.reference_position, message.position),
            np.subtract(message.reference_velocity, message.velocity),
        )
        return self._assemble(head.decode()[:-1] + ",", reference, feedback, error)


# -- tf2_msgs/msg/TFMessage --------------------------------------------------------------
def rotation_to_quaternion(m: Sequence[float]) -> tuple[float, float, float, float]:
    """Unit quaternion ``(x, y, z, w)`` of the rotation in a row-major 4x4 (or 3x4) matrix.

    Built from the largest of ``|w|, |x|, |y|, |z|``, so it is exact near
    half turns too (URDFs are full of ``rpy="3.14159 ..."``).
    """
    r00, r01, r02, _, r10, r11, r12, _, r20, r21, r22 = m[:11]
    trace = r00 + r11 + r22
    if trace > 0.0:
        s = 0.5 / math.sqrt(trace + 1.0)
        return (r21 - r12) * s, (r02 - r20) * s, (r10 - r01) * s, 0.25 / s
    if r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        return 0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s
    if r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        return (r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s
    s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
    return (r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s


def _transform_template(frame_id: str, child_frame_id: str) -> str:
    return (
        '{"header":{"stamp":{"sec":%d,"nanosec":%d,"nsec":%d},'
        f'"frame_id":{_literal(frame_id)}}},"child_frame_id":{_literal(child_frame_id)},'
        f'"transform":{{"translation":{{"x":{NUMBER},"y":{NUMBER},"z":{NUMBER}}},'
        f'"rotation":{{"x":{NUMBER},"y":{NUMBER},"z":{NUMBER},"w":{NUMBER}}}}}}}'
    )


class TFMessageEncoder:
    """``TFMessage`` -> ``tf2_msgs/msg/TFMessage`` (4x4 matrices as translation + quaternion)."""

    schema = TF_MESSAGE

    def __init__(self) -> None:
        self._templates: dict[tuple[tuple[str, str], ...], str] = {}

    def __call__(self, message: TFMessage) -> bytes:
        transforms = message.transforms
        key = tuple([(t.frame_id, t.child_frame_id) for t in transforms])
        template = self._templates.get(key)
        if template is None:
            parts = ",".join(_transform_template(parent, child) for parent, child in key)
            template = '{"transforms":[' + parts + "]}"
            self._templates[key] = template
        values: list[float | int] = []
        stamp, sec, nanosec = None, 0, 0
        for transform in transforms:
            row = np.asarray(transform.matrix, dtype=float).ravel().tolist()
            if len(row) != 16 or not math.isfinite(sum(row)):
                return self._slow(message)
            if transform.stamp != stamp:  # the transforms of a message share one, mostly
                stamp = transform.stamp
                sec, nanosec = _stamp(stamp)
            values += (sec, nanosec, nanosec, row[3], row[7], row[11])
            values += rotation_to_quaternion(row)
        return (template % tuple(values)).encode()

    def _slow(self, message: TFMessage) -> bytes:
        """The message without its transforms that are not 4x4 and finite (unknown poses
        are not published, as in ROS)."""
        transforms = []
        for transform in message.transforms:
            row = np.asarray(transform.matrix, dtype=float).ravel().tolist()
            if len(row) == 16 and all(math.isfinite(v) for v in row):
                transforms.append(self._plain(transform, row))
        return dumps({"transforms": transforms})

    @staticmethod
    def _plain(transform: Any, row: list[float]) -> dict[str, Any]:
        return {
            "header": header(transform.stamp, transform.frame_id),
            "child_frame_id": transform.child_frame_id,
            "transform": {
                "translation": dict(zip("xyz", (row[3], row[7], row[11]), strict=True)),
                "rotation": dict(zip("xyzw", rotation_to_quaternion(row), strict=True)),
            },
        }


# -- std_msgs ----------------------------------------------------------------------------
class JointCommandEncoder:
    """``JointCommand`` -> ``std_msgs/msg/Float64MultiArray``."""

    schema = FLOAT64_MULTI_ARRAY

    def __call__(self, message: JointCommand) -> bytes:
        return dumps(
            {"layout": {"dim": [], "data_offset": 0}, "data": finite_or_empty(message.positions)}
        )


class StringEncoder:
    """A ``str`` -> ``std_msgs/msg/String``."""

    schema = STRING

    def __call__(self, message: str) -> bytes:
        return dumps({"data": message})


# -- armfleet_msgs/msg/PlannedMotion ----------------------------------------------------
#: Frame of a planned motion's tool path.
WORLD_FRAME = "world"


class PlannedMotionEncoder:
    """``PlannedMotion`` -> ``armfleet_msgs/msg/PlannedMotion``: its joint path as a ROS
    ``trajectory_msgs/msg/JointTrajectory`` and its tool path as ``geometry_msgs/msg/Point``s
    (see :data:`~armfleet.recording.schemas.PLANNED_MOTION`).

    A waypoint holding a position that is not finite is written with empty positions,
    one whose time is not finite is left out, and a tool path holding such a value is
    written empty. A stamp that is not finite cannot be written (the recorder skips the
    message).
    """

    schema = PLANNED_MOTION

    def __call__(self, message: PlannedMotion) -> bytes:
        stamp = float(message.stamp)
        if not math.isfinite(stamp):
            raise ValueError(f"the stamp {stamp} is not finite")
        names = [str(name) for name in message.name]
        rows = np.asarray(message.positions, dtype=float).reshape(-1, len(names) or 1)
        points = []
        for row, time_s in zip(rows, message.time_from_start, strict=False):
            if not math.isfinite(time_s):
                continue
            sec, nanosec = _stamp(float(time_s))
            points.append(
                {
                    "positions": finite_or_empty(row),
                    "velocities": [],
                    "accelerations": [],
                    "effort": [],
                    "time_from_start": {"sec": sec, "nanosec": nanosec},
                }
            )
        tool = np.asarray(message.tool_path, dtype=float)
        tool_path = []
        if tool.ndim == 2 and tool.shape[1] == 3 and np.isfinite(tool).all():
            tool_path = [{"x": x, "y": y, "z": z} for x, y, z in tool.tolist()]
        return dumps(
            {
                "header": header(stamp, WORLD_FRAME),
                "trajectory": {"header": header(stamp), "joint_names": names, "points": points},
                "tool_path": tool_path,
            }
        )


def planned_motion(message: dict[str, Any]) -> PlannedMotion:
    """The :class:`PlannedMotion` of a recorded ``armfleet_msgs/msg/PlannedMotion``.

    Positions written empty read back as NaN (:func:`numbers_or_nan`).

    Raises:
        KeyError, TypeError, ValueError: ``message`` is not shaped like the schema.
    """
    stamp = message["header"]["stamp"]
    trajectory = message["trajectory"]
    names = tuple(str(name) for name in trajectory["joint_names"])
    points = trajectory["points"]
    times = tuple(
        p["time_from_start"]["sec"] + p["time_from_start"]["nanosec"] / NS_PER_S for p in points
    )
    positions = np.array(
        [numbers_or_nan(p["positions"], len(names)) for p in points], dtype=float
    ).reshape(len(points), len(names))
    tool_path = np.array(
        [(p["x"], p["y"], p["z"]) for p in message["tool_path"]], dtype=float
    ).reshape(-1, 3)
    return PlannedMotion(
        stamp["sec"] + stamp["nanosec"] / NS_PER_S, names, times, positions, tool_path
    )


# -- anything else -----------------------------------------------------------------------
class _NotFinite:
    """What :func:`plain` returns for a value holding a non-finite number."""


NOT_FINITE = _NotFinite()


def plain(value: Any) -> Any:
    """``value`` as JSON values: dataclasses as objects (``stamp`` as a ROS header),
    enums as their value, arrays as lists. A number, or a list of them, that is not all
    finite becomes :data:`NOT_FINITE`, and an object leaves such a field out."""
    if isinstance(value, bool | int | str) or value is None:
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else NOT_FINITE
    if isinstance(value, np.ndarray):
        return finite_or_none(value) if value.dtype.kind in "fiu" else plain(value.tolist())
    if isinstance(value, np.generic):
        return plain(value.item())
    if isinstance(value, enum.Enum):
        return plain(value.value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields: dict[str, Any] = {}
        for field in dataclasses.fields(value):
            item = getattr(value, field.name)
            if field.name == "stamp":
                fields["header"] = header(float(item))
            elif (written := plain(item)) is not NOT_FINITE:
                fields[field.name] = written
        return fields
    if isinstance(value, list | tuple):
        items = [plain(item) for item in value]
        return NOT_FINITE if any(item is NOT_FINITE for item in items) else items
    if isinstance(value, dict):
        pairs = {str(key): plain(item) for key, item in value.items()}
        return {key: item for key, item in pairs.items() if item is not NOT_FINITE}
    return str(value)


def finite_or_none(values: np.ndarray) -> Any:
    """A numeric array as a list, or NOT_FINITE if any value is not finite."""
    flat: list[float] = values.astype(float).ravel().tolist()
    return flat if all(math.isfinite(v) for v in flat) else NOT_FINITE


def _json_value(value: Any) -> Any:
    """:func:`plain`, with a top-level value that is not finite written as ``null``."""
    written = plain(value)
    return None if written is NOT_FINITE else written


class DataclassEncoder:
    """Any dataclass message -> ``armfleet_msgs/msg/<Class>`` (schema derived from it)."""

    def __init__(self, message_type: type) -> None:
        self.schema = dataclass_schema(message_type)

    def __call__(self, message: Any) -> bytes:
        return dumps(_json_value(message))


class AnyEncoder:
    """A message of no dataclass type: its JSON form, under a schema that admits anything."""

    def __init__(self, message_type: type) -> None:
        self.schema = MessageSchema(
            OWN_PACKAGE + message_type.__name__,
            {"title": message_type.__name__, "description": "any JSON value"},
        )

    def __call__(self, message: Any) -> bytes:
        return dumps(_json_value(message))


_ROS_ENCODERS: dict[type, Callable[[], MessageEncoder]] = {
    JointState: JointStateEncoder,
    ControllerState: ControllerStateEncoder,
    TFMessage: TFMessageEncoder,
    JointCommand: JointCommandEncoder,
    PlannedMotion: PlannedMotionEncoder,
}


def encoder_for(message_type: type) -> MessageEncoder:
    """A new encoder for messages of ``message_type`` (one per channel: it keeps templates)."""
    ros = _ROS_ENCODERS.get(message_type)
    if ros is not None:
        return ros()
    if dataclasses.is_dataclass(message_type):
        return DataclassEncoder(message_type)
    return AnyEncoder(message_type)
