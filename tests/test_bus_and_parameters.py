"""The in-process bus (delivery, unsubscribe, latching, types, names) and controller
parameters (shipped files, schema errors, per-arm overrides)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

import armfleet
from armfleet.controllers.parameters import controller_file, load_parameters
from armfleet.controllers.registry import CONTROLLER_TYPES
from armfleet.description.data_folders import data_dir
from armfleet.errors import ParameterError
from armfleet.messages import ControllerState, JointCommand, JointState
from armfleet.runtime.bus import Bus, TopicError

# -- bus ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Note:
    text: str


@dataclass(frozen=True)
class LoudNote(Note):
    """A subclass: still a Note, so it may travel on a Note topic."""


def test_every_subscriber_gets_every_message_in_order() -> None:
    bus = Bus()
    first: list[Note] = []
    second: list[Note] = []
    elsewhere: list[Note] = []
    bus.subscribe("/bob/notes", first.append)
    bus.subscribe("/bob/notes", second.append)
    bus.subscribe("/toby/notes", elsewhere.append)
    messages = [Note("a"), Note("b"), LoudNote("c")]
    for message in messages:
        bus.publish("/bob/notes", message)
    assert first == messages and second == messages
    assert elsewhere == []
    assert bus.topics["/bob/notes"] is Note  # the first message fixed the type


def test_cancelled_subscription_gets_nothing_more() -> None:
    bus = Bus()
    kept: list[Note] = []
    dropped: list[Note] = []
    subscription = bus.subscribe("/bob/notes", dropped.append)
    bus.subscribe("/bob/notes", kept.append)
    bus.publish("/bob/notes", Note("before"))
    subscription.cancel()
    subscription.cancel()  # twice is harmless
    bus.publish("/bob/notes", Note("after"))
    assert dropped == [Note("before")]
    assert kept == [Note("before"), Note("after")]


def test_a_callback_may_cancel_itself_while_being_called() -> None:
    bus = Bus()
    once: list[Note] = []
    always: list[Note] = []

    def first_only(message: Note) -> None:
        once.append(message)
        subscription.cancel()

    subscription = bus.subscribe("/bob/notes", first_only)
    bus.subscribe("/bob/notes", always.append)
    bus.publish("/bob/notes", Note("1"))
    bus.publish("/bob/notes", Note("2"))
    assert once == [Note("1")]
    assert always == [Note("1"), Note("2")]  # the cancel did not skip a neighbour


def test_a_subscriber_with_a_period_gets_one_instant_per_period() -> None:
    """Every message of a due instant (several publishers at one time), none between,
    while a plain subscriber gets everything; has_subscribers says no between instants."""
    now = [0.0]
    bus = Bus(clock=lambda: now[0])
    every: list[tuple[float, str]] = []
    paced: list[tuple[float, str]] = []
    bus.subscribe("/tf", lambda m: every.append((now[0], m)))
    bus.subscribe("/tf", lambda m: paced.append((now[0], m)), period_s=0.01)
    asked = []
    for step in range(50):  # 1 ms steps, two publishers per step
        now[0] = step * 0.001
        bus.publish("/tf", "bob")
        bus.publish("/tf", "toby")
    assert len(every) == 100
    assert [t for t, _ in paced[::2]] == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.04])
    assert [m for _, m in paced] == ["bob", "toby"] * 5
    alone = Bus(clock=lambda: now[0])
    alone.subscribe("/tf", lambda m: None, period_s=0.01)
    for step in range(50, 70):
        now[0] = step * 0.001
        asked.append(alone.has_subscribers("/tf"))
        if asked[-1]:
            alone.publish("/tf", "bob")
    assert asked == [True] + [False] * 9 + [True] + [False] * 9


@pytest.mark.parametrize("period", [0, -1.0, float("nan"), "1"])
def test_a_bad_period_is_refused(period: Any) -> None:
    with pytest.raises(armfleet.InvalidNumber, match="period_s"):
        Bus().subscribe("/tf", lambda m: None, period_s=period)


def test_latched_messages_replay_to_late_subscribers() -> None:
    bus = Bus()
    bus.publish("/tf_static", Note("bob"), latch=True)
    bus.publish("/tf_static", Note("volatile"))  # not latched: gone for late subscribers
    bus.publish("/tf_static", Note("toby"), latch=True)
    late: list[Note] = []
    bus.subscribe("/tf_static", late.append)
    assert late == [Note("bob"), Note("toby")]  # at once, in order
    bus.publish("/tf_static", Note("carol"), latch=True)
    assert late == [Note("bob"), Note("toby"), Note("carol")]  # no duplicates
    other: list[Note] = []
    bus.subscribe("/tf", other.append)
    assert other == []


def test_wrong_message_type_is_refused() -> None:
    bus = Bus()
    heard: list[Any] = []
    bus.advertise("/bob/position_controller/commands", JointCommand)
    bus.subscribe("/bob/position_controller/commands", heard.append)
    with pytest.raises(TopicError) as caught:
        bus.publish("/bob/position_controller/commands", Note("go"))
    assert "JointCommand" in str(caught.value) and "Note" in str(caught.value)
    assert heard == []
    with pytest.raises(TopicError):
        bus.advertise("/bob/position_controller/commands", JointState)
    bus.advertise("/bob/position_controller/commands", JointCommand)  # same type: fine
    bus.publish("/bob/notes", Note("x"))
    with pytest.raises(TopicError):
        bus.publish("/bob/notes", JointCommand((0.0,)))  # the first publish fixed Note


MALFORMED_TOPICS = {
    "empty": "",
    "relative": "bob/joint_states",
    "root-only": "/",
    "uppercase": "/Bob/joint_states",
    "trailing-slash": "/bob/",
    "double-slash": "/bob//joint_states",
    "dash": "/bob/joint-states",
    "leading-digit": "/1bob",
    "space": "/bob/joint states",
    "dot": "/bob/./joint_states",
    "trailing-newline": "/bob/joint_states\n",
}


@pytest.mark.parametrize(
    "topic",
    [
        pytest.param(
            topic,
            id=key,
        )
        for key, topic in MALFORMED_TOPICS.items()
    ],
)
@pytest.mark.parametrize("use", ["advertise", "subscribe", "publish"])
def test_malformed_topic_names_are_refused(topic: str, use: str) -> None:
    bus = Bus()
    with pytest.raises(TopicError) as caught:
        if use == "advertise":
            bus.advertise(topic, Note)
        elif use == "subscribe":
            bus.subscribe(topic, lambda message: None)
        else:
            bus.publish(topic, Note("x"))
    message = str(caught.value)
    assert "\n" not in message
    assert repr(topic) in message
    assert "/bob/joint_states" in message  # an example of a good name
    assert bus.topics == {}


@pytest.mark.parametrize("topic", ["/bob", "/bob/joint_states", "/a_1/b2/c_"])
def test_well_formed_topic_names_are_accepted(topic: str) -> None:
    bus = Bus()
    heard: list[Note] = []
    bus.subscribe(topic, heard.append)
    bus.publish(topic, Note("x"))
    assert heard == [Note("x")]


def test_joint_states_arrive_once_per_step_with_prefixed_names(world: armfleet.World) -> None:
    bob = world.spawn("bob")
    states: list[JointState] = []
    world.bus.subscribe("/bob/joint_states", states.append)
    steps = 100
    world.run(steps * world.dt)
    # publish_rate_hz 1000 at dt 1 ms: one message per step, stamped one dt apart.
    assert len(states) == steps
    stamps = np.array([s.stamp for s in states])
    assert np.allclose(np.diff(stamps), world.dt, rtol=0.0, atol=1e-12)
    assert all(name.startswith("bob_") for name in states[-1].name)
    assert set(bob.joint_names) <= set(states[-1].name)


# -- parameters -----------------------------------------------------------------------------

SHIPPED = sorted(data_dir("controllers").glob("*.yaml"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_file_validates_to_its_own_values(path: Path) -> None:
    document = yaml.safe_load(path.read_text())
    (controller,) = document  # one controller per file
    assert controller in CONTROLLER_TYPES, f"{path.name} names no controller type"
    schema = CONTROLLER_TYPES[controller].parameter_schema
    given = document[controller]
    values = load_parameters(controller, schema, path)
    assert set(values) == {spec.name for spec in schema}
    for spec in schema:
        assert values[spec.name] == given.get(spec.name, spec.default)


@pytest.mark.parametrize("controller", list(CONTROLLER_TYPES))
def test_every_controller_type_has_a_shipped_file_and_sane_defaults(controller: str) -> None:
    assert controller_file(controller).is_file()
    for spec in CONTROLLER_TYPES[controller].parameter_schema:
        assert spec.lower <= spec.default <= spec.upper, spec.name
        assert spec.description, spec.name


POSITION = "position_controller"
POSITION_SCHEMA = CONTROLLER_TYPES[POSITION].parameter_schema

#: id -> (value line under position_controller:, fragments of the error)
BAD_FILE_LINES = {
    "unknown-key": (
        "max_acceleration: 2.0",
        ["unknown position_controller parameter 'max_acceleration'",
         "did you mean 'max_acceleration_rad_s2'?", "valid: ", "kd_s"],
    ),
    "unknown-key-no-close-match": ("zzz: 1.0", ["'zzz'", "valid: ", "kp_s2"]),
    "below-lower-bound": ("kp_s2: -1.0", ["kp_s2 = -1.0", "outside [0, "]),
    "above-upper-bound": ("velocity_scaling: 1.5", ["velocity_scaling = 1.5", "outside [0.01, 1]"]),
    "string": ("kp_s2: fast", ["kp_s2 = 'fast'", "finite number"]),
    "quoted-number": ("kp_s2: '900'", ["kp_s2 = '900'", "finite number"]),
    "bool": ("kd_s: true", ["kd_s = True", "finite number"]),
    "null": ("kd_s:", ["kd_s = None", "finite number"]),
    "nan": ("kd_s: .nan", ["kd_s = nan", "finite number"]),
    "list": ("kd_s: [1, 2]", ["kd_s = [1, 2]", "finite number"]),
}  # fmt: skip


@pytest.mark.parametrize("case", list(BAD_FILE_LINES))
def test_bad_value_in_a_file_names_file_line_and_choices(tmp_path: Path, case: str) -> None:
    line, fragments = BAD_FILE_LINES[case]
    path = tmp_path / "mine.yaml"
    path.write_text(f"# my gains\n{POSITION}:\n  update_rate_hz: 1000.0\n  {line}\n")
    with pytest.raises(ParameterError) as caught:
        load_parameters(POSITION, POSITION_SCHEMA, path)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:4: ")  # the offending line
    for fragment in fragments:
        assert fragment in message


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("position_controller: [kp_s2\n", "not valid YAML"),
        ("joint_state_broadcaster:\n  publish_rate_hz: 100\n", "no 'position_controller:' section"),
        ("position_controller: 5\n", "expected parameters as a mapping"),
    ],
    ids=["not-yaml", "no-section", "section-not-a-mapping"],
)
def test_malformed_file_is_refused(tmp_path: Path, text: str, fragment: str) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    with pytest.raises(ParameterError) as caught:
        load_parameters(POSITION, POSITION_SCHEMA, path)
    assert str(path) in str(caught.value) and fragment in str(caught.value)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    ("override", "fragment"),
    [
        ({"max_jerk": 10.0}, "did you mean 'max_jerk_rad_s3'?"),
        ({"max_jerk_rad_s3": 0.0}, "max_jerk_rad_s3 = 0.0 is outside [0.001, 1e+06]"),
        ({"max_jerk_rad_s3": "10"}, "max_jerk_rad_s3 = '10' must be a finite number"),
        ({"max_jerk_rad_s3": float("inf")}, "max_jerk_rad_s3 = inf must be a finite number"),
    ],
    ids=["unknown-key", "out-of-bounds", "string", "inf"],
)
def test_bad_override_is_refused(override: dict[str, object], fragment: str) -> None:
    with pytest.raises(ParameterError) as caught:
        load_parameters(POSITION, POSITION_SCHEMA, overrides=override)
    assert str(caught.value).startswith("override: ")
    assert fragment in str(caught.value)


def test_override_wins_over_the_file() -> None:
    values = load_parameters(POSITION, POSITION_SCHEMA, overrides={"kp_s2": 900})
    shipped = load_parameters(POSITION, POSITION_SCHEMA)
    assert values == {**shipped, "kp_s2": 900.0}


#: toby's acceleration limit [rad/s^2]; the shipped file gives 5.0.
TOBY_ACCELERATION = 2.0
#: Ruckig's reference keeps to its limits up to rounding [rad/s^2].
LIMIT_ROUNDING = 1e-6


@pytest.fixture(scope="module")
def overridden() -> Any:
    """bob with the shipped parameters, toby with his own acceleration limit; both
    make the same 1 rad move of joint 1 while their references are recorded."""
    with armfleet.World() as world:
        bob = world.spawn("bob", at=(0, 0))
        toby = world.spawn(
            "toby",
            at=(1, 0),
            parameters={POSITION: {"max_acceleration_rad_s2": TOBY_ACCELERATION}},
        )
        references: dict[str, list[ControllerState]] = {"bob": [], "toby": []}
        for arm in (bob, toby):
            world.bus.subscribe(
                f"/{arm.name}/position_controller/state", references[arm.name].append
            )
            target = arm.positions
            target[0] += 1.0
            arm.move_to(target)
        while bob.is_moving or toby.is_moving:
            assert world.time < 10.0
            world.run(0.05)
        yield world, references


def test_override_applies_to_its_arm_only(overridden: Any) -> None:
    world, _ = overridden
    shipped = load_parameters(POSITION, POSITION_SCHEMA, controller_file(POSITION))
    assert world.arm("bob").position_controller.parameters == shipped
    assert world.arm("toby").position_controller.parameters == {
        **shipped,
        "max_acceleration_rad_s2": TOBY_ACCELERATION,
    }
    # Broadcasters were not overridden: both keep the shipped file.
    broadcaster = "joint_state_broadcaster"
    shipped_broadcaster = load_parameters(
        broadcaster, CONTROLLER_TYPES[broadcaster].parameter_schema
    )
    assert world.arm("bob").broadcaster.parameters == shipped_broadcaster
    assert world.arm("toby").broadcaster.parameters == shipped_broadcaster


def test_each_arm_moves_within_its_own_acceleration_limit(overridden: Any) -> None:
    world, references = overridden
    peak = {
        name: max(float(np.abs(s.reference_acceleration).max()) for s in states)
        for name, states in references.items()
    }
    shipped = world.arm("bob").position_controller.parameters["max_acceleration_rad_s2"]
    assert peak["toby"] <= TOBY_ACCELERATION + LIMIT_ROUNDING
    assert peak["toby"] > 0.9 * TOBY_ACCELERATION  # a 1 rad move uses the limit
    assert peak["bob"] <= shipped + LIMIT_ROUNDING
    assert peak["bob"] > 0.9 * shipped  # bob was not slowed to toby's limit
    # Both arrive: toby later.
    done = {
        name: next(s.stamp for s in states[1:] if not s.moving)
        for name, states in references.items()
    }
    assert done["toby"] > done["bob"]


def test_broadcaster_rate_override_is_per_arm(world: armfleet.World) -> None:
    world.spawn("bob")
    world.spawn(
        "toby", at=(1, 0), parameters={"joint_state_broadcaster": {"publish_rate_hz": 100.0}}
    )
    heard: dict[str, list[JointState]] = {"bob": [], "toby": []}
    for name, messages in heard.items():
        world.bus.subscribe(f"/{name}/joint_states", messages.append)
    world.run(0.5)
    # 1000 Hz and 100 Hz over 0.5 s
    assert {name: len(messages) for name, messages in heard.items()} == {"bob": 500, "toby": 50}
