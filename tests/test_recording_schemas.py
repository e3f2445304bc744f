"""Every recorded message validates against its own channel's JSON Schema.

One recording exercises every topic armfleet publishes: two arms moving until they touch
(protective stop, ``/collisions``), a gripper closing and opening, a dynamic object on
``/tf``, planned motions (one with a tool path that is not finite), non-finite commands
sent on the bus (refused, but recorded), and an arm whose
controller produces non-finite torques (error). Every message of every channel is checked
with ``jsonschema`` against the schema record of its channel, read with the official
``mcap`` reader; and the schemas stay readable by Foxglove (one JSON type per field).

``jsonschema`` is run once per class of messages its checks cannot tell apart (same keys,
lengths, texts and booleans, and numbers of the same JSON type on the same side of every
bound the schema names), which is what those checks see of a message: the verdict on
one is the verdict on all of its class (30,000 messages, a few thousand classes).
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import jsonschema  # type: ignore[import-untyped]
import numpy as np
import pytest
from mcap.reader import make_reader

import armfleet
from armfleet.messages import ArmMode, ControllerState, GripperCommand, JointCommand, JointState
from armfleet.recording.encode import encoder_for, numbers_or_nan
from tests.viewer_helpers import straight_plan

#: control_msgs/msg/JointTrajectoryControllerState in ROS 2 Humble (rosidl field order).
HUMBLE_CONTROLLER_STATE_FIELDS = (
    "header", "joint_names", "reference", "feedback", "error", "output", "desired", "actual",
    "multi_dof_joint_names", "multi_dof_reference", "multi_dof_feedback", "multi_dof_error",
    "multi_dof_output", "multi_dof_desired", "multi_dof_actual",
)  # fmt: skip
#: trajectory_msgs/msg/JointTrajectoryPoint.
POINT_FIELDS = ("positions", "velocities", "accelerations", "effort", "time_from_start")
MULTI_DOF_POINT_FIELDS = ("transforms", "velocities", "accelerations", "time_from_start")


@dataclass
class Recorded:
    path: Path
    topics: set[str]
    statuses: list[Any]


def lean_forward(arm: armfleet.Arm) -> np.ndarray:
    target = arm.positions.copy()
    target[1] += 1.0  # shoulder forward
    target[3] += 1.2  # elbow open
    return target


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Recorded]:
    path = tmp_path_factory.mktemp("schemas") / "everything.mcap"
    statuses: list[Any] = []
    with armfleet.World() as world:
        recorder = armfleet.record(world, path)  # before the arms: /bringup too
        world.bus.subscribe_all(lambda t, m: statuses.append(m) if t.endswith("/status") else None)
        bob = world.spawn("bob", at=(0, 0))
        toby = world.spawn("toby", at=(0.8, 0, 0, 180))  # facing bob, close enough to touch
        world.add_object("cube", "box", size=(0.05, 0.05, 0.05), mass=0.1, at=(0.4, -0.5, 0.025))
        bob.gripper.close()
        toby.gripper.move_to(0.02)
        world.run(0.3)
        bob.gripper.open()
        # Non-finite commands on the bus: refused by the controllers, recorded as sent.
        world.bus.publish("/bob/position_controller/commands", JointCommand((math.nan,) * 7))
        world.bus.publish(
            "/bob/gripper_controller/commands", GripperCommand(math.inf, False, math.nan)
        )
        # Planned motions as they start (toby's with a tool path that is not finite).
        world.bus.publish("/bob/planned_motion", straight_plan(world, bob, lean_forward(bob)))
        plan = straight_plan(world, toby, lean_forward(toby))
        world.bus.publish("/toby/planned_motion", replace(plan, tool_path=plan.tool_path * np.nan))
        bob.move_to(lean_forward(bob))
        toby.move_to(lean_forward(toby))
        world.run(2.5)  # they touch: protective stop
        bob.reset()
        toby.reset()
        toby.position_controller._kp[:] = math.nan  # a controller gone wrong: NaN torques
        toby.move_to(toby.positions + 0.1)
        world.run(0.2)
        topics = set(world.bus.topics)
        recorder.stop()
    yield Recorded(path, topics, statuses)


def channels_and_messages(path: Path) -> tuple[dict[str, Any], dict[str, list[Any]]]:
    """(JSON Schema by topic, decoded messages by topic), all from the official reader."""
    schemas: dict[str, Any] = {}
    messages: dict[str, list[Any]] = {}
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        for channel in summary.channels.values():
            record = summary.schemas[channel.schema_id]
            assert record.encoding == "jsonschema" and channel.message_encoding == "json"
            schemas[channel.topic] = json.loads(record.data)
            messages[channel.topic] = []
        for _, channel, message in reader.iter_messages(log_time_order=False):
            messages[channel.topic].append(json.loads(message.data))
    return schemas, messages


@pytest.fixture(scope="module")
def contents(recorded: Recorded) -> tuple[dict[str, Any], dict[str, list[Any]]]:
    return channels_and_messages(recorded.path)


def test_the_run_exercised_every_case(recorded: Recorded, contents: Any) -> None:
    """What the validation below must cover did happen: else it proves little."""
    _, messages = contents
    assert recorded.topics <= set(messages)
    for topic in recorded.topics:
        assert messages[topic], f"nothing recorded on {topic}"
    modes = {s.mode for s in recorded.statuses}
    assert {ArmMode.MOVING, ArmMode.PROTECTIVE_STOP, ArmMode.ERROR} <= modes
    assert any(m["contacts"] for m in messages["/collisions"])
    assert any(t["child_frame_id"] == "cube" for m in messages["/tf"] for t in m["transforms"])
    assert any(m["data"] == [] for m in messages["/bob/position_controller/commands"])
    assert messages["/toby/planned_motion"][0]["tool_path"] == []
    gripper_commands = messages["/bob/gripper_controller/commands"]
    assert any("width" not in m and "force" not in m for m in gripper_commands)
    # toby's NaN torques never reach /toby/joint_states: the fault replaces them first.
    assert all(len(m["effort"]) == len(m["name"]) for m in messages["/toby/joint_states"])


#: The keywords whose checks see only what :func:`validation_class` keeps of a message.
#: A schema with any other keyword (a ``pattern``, ``uniqueItems``, ...) has every one of
#: its messages validated.
CLASSED_KEYWORDS = frozenset(
    ("$schema", "title", "description", "type", "properties", "required", "items",
     "minItems", "maxItems", "minimum", "maximum", "enum")
)  # fmt: skip
#: Every this many messages of a topic are validated themselves too, whatever their class.
SAMPLE_EVERY = 50


def bounds_if_classable(schema: Any) -> tuple[float, ...] | None:
    """The numbers ``schema`` compares values with (minimum, maximum, enum), sorted; None
    if it has a keyword outside :data:`CLASSED_KEYWORDS` or an enum of other values."""
    bounds: set[float] = set()
    todo = [schema]
    while todo:
        node = todo.pop()
        if not isinstance(node, dict) or not set(node) <= CLASSED_KEYWORDS:
            return None
        for keyword, value in node.items():
            if keyword == "properties":
                todo.extend(value.values())
            elif keyword == "items":
                todo.append(value)
            elif keyword in ("minimum", "maximum"):
                bounds.add(value)
            elif keyword == "enum":
                if not all(v is None or isinstance(v, str | int | float) for v in value):
                    return None
                bounds.update(v for v in value if type(v) in (int, float))
    return tuple(sorted(bounds))


def validation_class(value: Any, bounds: tuple[float, ...]) -> Any:
    """What a schema of :data:`CLASSED_KEYWORDS` with these ``bounds`` can see of ``value``:
    keys, lengths, texts and booleans as they are; a finite number as its JSON type
    ("integer" includes 2.0, as for jsonschema) and its side of each bound; other numbers
    (NaN, infinities) as they are."""
    kind = type(value)
    if kind is dict:
        return ("object", *((key, validation_class(v, bounds)) for key, v in sorted(value.items())))
    if kind is list:
        return ("array", *(validation_class(v, bounds) for v in value))
    if kind is int or (kind is float and math.isfinite(value)):
        integer = kind is int or value.is_integer()
        return ("integer" if integer else "number", *((value > b) - (value < b) for b in bounds))
    if kind is float:
        return ("non-finite", repr(value))
    return (kind.__name__, value)  # str, bool, None: as they are


def test_messages_of_one_class_get_one_verdict() -> None:
    """The classes keep apart what jsonschema tells apart."""
    schema = {"type": "object", "properties": {"n": {"type": "integer", "minimum": 0}}}
    assert bounds_if_classable(schema) == (0,)
    bounds = (0.0,)
    validator = jsonschema.Draft202012Validator(schema)
    values = [-1, 0, 1, 2, 2.0, 2.5, -0.5, True, False, None, "2", math.nan, math.inf, [2]]
    by_class: dict[Any, set[bool]] = {}
    for value in values:
        verdict = validator.is_valid({"n": value})
        by_class.setdefault(validation_class({"n": value}, bounds), set()).add(verdict)
    assert all(len(verdicts) == 1 for verdicts in by_class.values())
    assert validation_class({"n": 2}, bounds) == validation_class({"n": 2.0}, bounds)
    assert validation_class([1, 2], bounds) != validation_class([1, 2, 3], bounds)
    assert validation_class({"a": 1}, bounds) != validation_class({"b": 1}, bounds)
    assert validation_class(True, bounds) != validation_class(1, bounds)
    assert bounds_if_classable({"type": "string", "pattern": "^a"}) is None


def test_every_message_validates_against_its_channels_schema(contents: Any) -> None:
    schemas, messages = contents
    checked = Counter[str]()
    for topic, schema in schemas.items():
        jsonschema.Draft202012Validator.check_schema(schema)
        validator = jsonschema.Draft202012Validator(schema)
        bounds = bounds_if_classable(schema)
        if bounds is None:
            to_validate = messages[topic]
        else:  # the first message of each class, and a sample of the others
            classes: dict[Any, Any] = {}
            for message in messages[topic]:
                classes.setdefault(validation_class(message, bounds), message)
            to_validate = [*classes.values(), *messages[topic][::SAMPLE_EVERY]]
        for message in to_validate:
            errors = list(validator.iter_errors(message))
            assert not errors, f"{topic}: {errors[0].message} at {list(errors[0].path)}"
        checked[topic] += len(messages[topic])
    print(dict(checked))
    assert sum(checked.values()) == sum(len(m) for m in messages.values()) > 10_000


def every_field_type(schema: Any, where: str = "") -> Iterator[tuple[str, Any]]:
    """(path, ``type``) of every property and array item, as Foxglove walks a schema."""
    for name, field in schema.get("properties", {}).items():
        yield f"{where}.{name}", field.get("type")
        if field.get("type") == "object":
            yield from every_field_type(field, f"{where}.{name}")
        if field.get("type") == "array":
            items = field.get("items", {})
            yield f"{where}.{name}[]", items.get("type")
            if items.get("type") == "object":
                yield from every_field_type(items, f"{where}.{name}[]")


def test_every_field_has_one_json_type_as_foxglove_needs(contents: Any) -> None:
    """Foxglove's JSON Schema reader takes a field's ``type`` as one string (boolean,
    string, number, integer, object, array) and refuses the channel otherwise."""
    schemas, _ = contents
    allowed = {"boolean", "string", "number", "integer", "object", "array"}
    for topic, schema in schemas.items():
        assert schema["type"] == "object"
        for where, kind in every_field_type(schema):
            assert kind in allowed, f"{topic}: {where} has type {kind!r}"


def test_the_controller_state_is_the_whole_ros_message(contents: Any) -> None:
    _, messages = contents
    for message in messages["/bob/position_controller/state"][::97]:
        assert tuple(message) == HUMBLE_CONTROLLER_STATE_FIELDS
        for part in ("reference", "feedback", "error", "output", "desired", "actual"):
            assert tuple(message[part]) == POINT_FIELDS
            assert tuple(message[f"multi_dof_{part}"]) == MULTI_DOF_POINT_FIELDS
        assert message["desired"] == message["reference"]
        assert message["actual"] == message["feedback"]
        n = len(message["joint_names"])
        reference, feedback = message["reference"], message["feedback"]
        for key in ("positions", "velocities"):
            expected = np.subtract(reference[key], feedback[key])
            assert message["error"][key] == pytest.approx(expected.tolist(), abs=1e-15)
            assert len(reference[key]) == n
        assert len(reference["accelerations"]) == n and feedback["accelerations"] == []


def test_non_finite_values_are_left_out_and_read_back_as_nan() -> None:
    state = JointState(
        1.5, ("a", "b"), np.array([0.1, np.nan]), np.array([0.0, 0.0]), np.array([np.inf, 1.0])
    )
    message = json.loads(encoder_for(JointState)(state))
    assert message["position"] == [] and message["effort"] == []  # "not available" in ROS
    assert message["velocity"] == [0.0, 0.0]
    assert numbers_or_nan(message["position"], 2) == pytest.approx([math.nan] * 2, nan_ok=True)
    assert numbers_or_nan([0.5, None], 2) == pytest.approx([0.5, math.nan], nan_ok=True)

    fine, broken = np.array([0.1, 0.2]), np.array([np.nan, 0.2])  # a measured position
    controller_state = ControllerState(0.5, ("a", "b"), fine, fine, fine, broken, fine, False)
    controller = json.loads(encoder_for(ControllerState)(controller_state))
    assert controller["feedback"]["positions"] == [] and controller["error"]["positions"] == []
    assert controller["reference"]["positions"] == [0.1, 0.2]

    command = json.loads(encoder_for(GripperCommand)(GripperCommand(math.nan, True, 20.0)))
    assert command == {"grasp": True, "force": 20.0}
