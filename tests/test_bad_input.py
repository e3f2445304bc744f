"""Invariant 4: bad input gets a one-line error naming the problem and the valid choices,
and leaves the world untouched.

"Untouched" means: the same arms, the same number of PyBullet bodies, the same
simulated time, bob's position-controller reference and target unchanged, nothing
sent on ``/bob/position_controller/commands``, and bob still holding: over the
next 0.2 s his joints stay within 1e-4 rad of where they were (the tracking
figure of issue #2 for a settled arm). Afterwards a valid spawn or move works.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.checks.names import ARM_NAME_PATTERN
from armfleet.controllers import PositionController
from armfleet.errors import (
    ArmfleetError,
    DescriptionError,
    DuplicateArmName,
    InvalidArmName,
    JointLimitError,
    NonFiniteTarget,
    ParameterError,
    PoseError,
    TargetLengthError,
    TargetTypeError,
    UnknownModel,
)
from armfleet.messages import FloatArray, JointCommand

#: A settled arm's joints drift less than this over HOLD_CHECK_S [rad].
HOLD_DRIFT_RAD = 1e-4
HOLD_CHECK_S = 0.2
#: A finished move ends within the controller's holding tolerance of its target [rad].
ARRIVAL_RAD = 1e-3
#: Distance past a limit for "just outside" targets [rad].
JUST_OUTSIDE_RAD = 1e-3

# Joints of the Panda with one-sided limits: joint4 in [-3.0718, -0.0698], joint6 in
# [-0.0175, 3.7525]; their indices in Arm.joint_names.
JOINT4, JOINT6 = 3, 5


@dataclass
class Scene:
    world: armfleet.World
    bob: armfleet.Arm
    commands: list[JointCommand] = field(default_factory=list)


@pytest.fixture
def scene(world: armfleet.World) -> Scene:
    """bob, a Panda at the origin, ready and holding; commands to him are recorded."""
    bob = world.spawn("bob")
    scene = Scene(world, bob)
    world.bus.subscribe("/bob/position_controller/commands", scene.commands.append)
    return scene


@dataclass(frozen=True)
class Snapshot:
    arms: tuple[str, ...]
    bodies: int
    time: float
    reference: tuple[FloatArray, FloatArray, FloatArray]
    target: tuple[float, ...]
    positions: FloatArray
    moving: bool


def take_snapshot(scene: Scene) -> Snapshot:
    trajectory = scene.bob.position_controller.trajectory
    assert trajectory is not None
    return Snapshot(
        arms=tuple(scene.world.arms),
        bodies=p.getNumBodies(physicsClientId=scene.world.physics_client),
        time=scene.world.time,
        reference=(
            trajectory.position.copy(),
            trajectory.velocity.copy(),
            trajectory.acceleration.copy(),
        ),
        target=tuple(trajectory._input.target_position),
        positions=scene.bob.positions,
        moving=scene.bob.is_moving,
    )


def assert_untouched(before: Snapshot, after: Snapshot) -> None:
    assert after.arms == before.arms
    assert after.bodies == before.bodies
    assert after.time == before.time
    for old, new in zip(before.reference, after.reference, strict=True):
        np.testing.assert_array_equal(new, old)
    assert after.target == before.target
    np.testing.assert_array_equal(after.positions, before.positions)
    assert after.moving == before.moving


def limits(bob: armfleet.Arm, index: int) -> str:
    """A joint's name and limits as the errors print them."""
    lower, upper = bob.joint_limits
    return (
        f"{bob.joint_names[index]} is outside its limits [{lower[index]:.6g}, {upper[index]:.6g}]"
    )


def with_value(bob: armfleet.Arm, index: int, value: float) -> FloatArray:
    """bob's current positions with joint ``index`` set to ``value``."""
    target = bob.positions
    target[index] = value
    return target


def just_above_upper(bob: armfleet.Arm, index: int) -> FloatArray:
    return with_value(bob, index, bob.joint_limits[1][index] + JUST_OUTSIDE_RAD)


def just_below_lower(bob: armfleet.Arm, index: int) -> FloatArray:
    return with_value(bob, index, bob.joint_limits[0][index] - JUST_OUTSIDE_RAD)


Action = Callable[[armfleet.World, armfleet.Arm], object]
Expect = Callable[[armfleet.World, armfleet.Arm], Sequence[str]]


@dataclass(frozen=True)
class BadInput:
    """Something a user gets wrong, the error it must raise and what its message must say."""

    action: Action
    error: type[ArmfleetError]
    expect: Expect


def spawn_toby(**kwargs: object) -> Action:
    def action(world: armfleet.World, bob: armfleet.Arm) -> object:
        arguments: dict[str, object] = {"name": "toby", "at": (1, 0), **kwargs}
        return world.spawn(**arguments)  # type: ignore[arg-type]

    return action


def move_bob(target: Callable[[armfleet.Arm], object]) -> Action:
    def action(world: armfleet.World, bob: armfleet.Arm) -> object:
        bob.move_to(target(bob))  # type: ignore[arg-type]
        return None

    return action


def name_error(name: str, label: str):  # -> a pytest.param
    return pytest.param(
        BadInput(
            spawn_toby(name=name), InvalidArmName, lambda w, b: [repr(name), ARM_NAME_PATTERN]
        ),
        id=f"name-{label}",
    )


def missing_model_file(model: str, label: str):  # -> a pytest.param
    """A path (or a description file's name) is a model file of one's own: one that is not
    there is refused as such, naming it (docs/own-robot.md)."""
    return pytest.param(
        BadInput(
            spawn_toby(model=model),
            DescriptionError,
            lambda w, b: [f"model file {model!r} not found"],
        ),
        id=f"unknown-model-{label}",
    )


def model_error(model: str, label: str):  # -> a pytest.param
    return pytest.param(
        BadInput(
            spawn_toby(model=model),
            UnknownModel,
            lambda w, b: [f"model {model!r} not found", "available: " + ", ".join(w.models.names)],
        ),
        id=f"unknown-model-{label}",
    )


def override(controller: str, key: str, value: object) -> Action:
    return spawn_toby(parameters={controller: {key: value}})


ACCELERATION = next(
    spec for spec in PositionController.parameter_schema if spec.name == "max_acceleration_rad_s2"
)
ACCELERATION_BOUNDS = f"outside [{ACCELERATION.lower:g}, {ACCELERATION.upper:g}]"

SPAWN_CASES = [
    model_error("pand", "typo"),
    model_error("Panda", "uppercase"),
    missing_model_file("panda.urdf.xacro", "file-name"),
    missing_model_file("../description/panda", "path"),
    model_error("", "empty"),
    pytest.param(
        BadInput(spawn_toby(name="bob"), DuplicateArmName, lambda w, b: ["'bob'", "arms: bob"]),
        id="duplicate-name",
    ),
    name_error("Toby", "uppercase"),
    name_error("1toby", "leading-digit"),
    name_error("", "empty"),
    name_error("world", "world"),
    name_error("to/by", "slash"),
    name_error("to-by", "dash"),
    pytest.param(
        BadInput(spawn_toby(at=(1,)), PoseError, lambda w, b: ["(x, y[, z[, yaw_deg]])"]),
        id="at-too-short",
    ),
    pytest.param(
        BadInput(
            spawn_toby(at=(1, 0, 0, 90, 0)), PoseError, lambda w, b: ["(x, y[, z[, yaw_deg]])"]
        ),
        id="at-too-long",
    ),
    pytest.param(
        BadInput(spawn_toby(at=(math.nan, 0)), PoseError, lambda w, b: ["x is nan", "finite"]),
        id="at-nan",
    ),
    pytest.param(
        BadInput(
            spawn_toby(at=(1, 0, 0, math.inf)), PoseError, lambda w, b: ["yaw is inf", "finite"]
        ),
        id="at-inf-yaw",
    ),
    pytest.param(
        BadInput(spawn_toby(at=("one", 0)), PoseError, lambda w, b: ["'one'", "numbers"]),
        id="at-not-numbers",
    ),
    pytest.param(
        BadInput(
            spawn_toby(initial_positions=[0.0] * 6),
            TargetLengthError,
            lambda w, b: ["toby: got 6", "expected 7", "toby_panda_joint1"],
        ),
        id="initial-too-few",
    ),
    pytest.param(
        BadInput(
            spawn_toby(initial_positions=[math.nan] * 7),
            NonFiniteTarget,
            lambda w, b: ["toby_panda_joint1", "nan", "finite"],
        ),
        id="initial-nan",
    ),
    pytest.param(
        BadInput(
            lambda w, b: w.spawn("toby", at=(1, 0), initial_positions=just_above_upper(b, JOINT4)),
            JointLimitError,
            lambda w, b: ["toby: ", limits(b, JOINT4).replace("bob_", "toby_")],
        ),
        id="initial-above-upper",
    ),
    pytest.param(
        BadInput(
            spawn_toby(initial_positions=["zero"] * 7),
            TargetTypeError,
            lambda w, b: ["numbers", "toby_panda_joint7"],
        ),
        id="initial-not-numbers",
    ),
    pytest.param(
        BadInput(
            spawn_toby(parameters={"velocity_controller": {}}),
            ParameterError,
            lambda w, b: [
                "velocity_controller",
                "joint_state_broadcaster, position_controller, gripper_controller",
            ],
        ),
        id="override-unknown-controller",
    ),
    pytest.param(
        BadInput(
            override("position_controller", "max_acceleration", 2.0),
            ParameterError,
            lambda w, b: [
                "unknown position_controller parameter 'max_acceleration'",
                "did you mean 'max_acceleration_rad_s2'?",
                "valid: ",
                "kp_s2",
            ],
        ),
        id="override-unknown-key",
    ),
    pytest.param(
        BadInput(
            override("position_controller", "max_acceleration_rad_s2", 0.0),
            ParameterError,
            lambda w, b: ["max_acceleration_rad_s2 = 0.0", ACCELERATION_BOUNDS],
        ),
        id="override-out-of-bounds",
    ),
    pytest.param(
        BadInput(
            override("joint_state_broadcaster", "publish_rate_hz", 0),
            ParameterError,
            lambda w, b: ["joint_state_broadcaster.publish_rate_hz = 0", "outside [1, "],
        ),
        id="override-broadcaster-out-of-bounds",
    ),
    pytest.param(
        BadInput(
            override("position_controller", "max_acceleration_rad_s2", "fast"),
            ParameterError,
            lambda w, b: ["max_acceleration_rad_s2 = 'fast'", "finite number"],
        ),
        id="override-not-a-number",
    ),
    pytest.param(
        BadInput(
            override("position_controller", "kp_s2", True),
            ParameterError,
            lambda w, b: ["kp_s2 = True", "finite number"],
        ),
        id="override-bool",
    ),
    pytest.param(
        BadInput(
            override("position_controller", "kp_s2", math.nan),
            ParameterError,
            lambda w, b: ["kp_s2 = nan", "finite number"],
        ),
        id="override-nan",
    ),
    pytest.param(
        BadInput(
            spawn_toby(parameters={"position_controller": ["kp_s2"]}),
            ParameterError,
            lambda w, b: ["position_controller"],
        ),
        id="override-not-a-mapping",
    ),
]

MOVE_CASES = [
    pytest.param(
        BadInput(
            move_bob(lambda b: b.positions[:-1]),
            TargetLengthError,
            lambda w, b: ["bob: got 6", "expected 7", ", ".join(b.joint_names)],
        ),
        id="target-too-few",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: [*b.positions, 0.0]),
            TargetLengthError,
            lambda w, b: ["bob: got 8", "expected 7", ", ".join(b.joint_names)],
        ),
        id="target-too-many",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: with_value(b, 2, math.nan)),
            NonFiniteTarget,
            lambda w, b: [f"target for {b.joint_names[2]} is nan", "finite"],
        ),
        id="target-nan",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: with_value(b, 0, math.inf)),
            NonFiniteTarget,
            lambda w, b: [f"target for {b.joint_names[0]} is inf", "finite"],
        ),
        id="target-plus-inf",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: with_value(b, 6, -math.inf)),
            NonFiniteTarget,
            lambda w, b: [f"target for {b.joint_names[6]} is -inf", "finite"],
        ),
        id="target-minus-inf",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: just_above_upper(b, JOINT4)),
            JointLimitError,
            lambda w, b: [limits(b, JOINT4)],
        ),
        id="target-just-above-upper",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: just_below_lower(b, JOINT6)),
            JointLimitError,
            lambda w, b: [limits(b, JOINT6)],
        ),
        id="target-just-below-lower",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: [0.0, "x", 0.0, -1.0, 0.0, 1.0, 0.0]),
            TargetTypeError,
            lambda w, b: ["numbers", ", ".join(b.joint_names)],
        ),
        id="target-not-numbers",
    ),
    pytest.param(
        BadInput(
            move_bob(lambda b: {"joint1": 0.0}),
            TargetTypeError,
            lambda w, b: ["numbers", ", ".join(b.joint_names)],
        ),
        id="target-a-dict",
    ),
]


def check_rejected(scene: Scene, case: BadInput) -> None:
    """The error, its one-line message, and the world untouched, bob holding."""
    world, bob = scene.world, scene.bob
    before = take_snapshot(scene)
    with pytest.raises(ArmfleetError) as caught:
        case.action(world, bob)
    assert type(caught.value) is case.error
    message = str(caught.value)
    assert "\n" not in message
    for fragment in case.expect(world, bob):
        assert fragment in message
    assert_untouched(before, take_snapshot(scene))
    assert scene.commands == []

    world.run(HOLD_CHECK_S)
    assert np.abs(bob.positions - before.positions).max() < HOLD_DRIFT_RAD
    assert not bob.is_moving
    assert bob.position_controller.is_holding


@pytest.mark.parametrize("case", SPAWN_CASES)
def test_bad_spawn_is_refused_and_world_untouched(scene: Scene, case: BadInput) -> None:
    check_rejected(scene, case)
    # The failed name is free: toby comes up as asked for the second time.
    toby = scene.world.spawn("toby", at=(1, 0))
    assert list(scene.world.arms) == ["bob", "toby"]
    assert p.getNumBodies(physicsClientId=scene.world.physics_client) == 3  # ground, bob, toby
    assert toby.position_controller.is_holding


def move_and_arrive(world: armfleet.World, bob: armfleet.Arm, target: FloatArray) -> None:
    bob.move_to(target)
    assert bob.is_moving
    deadline = world.time + 5.0
    while bob.is_moving and world.time < deadline:
        world.run(0.05)
    world.run(HOLD_CHECK_S)
    assert np.abs(bob.positions - target).max() < ARRIVAL_RAD


@pytest.mark.parametrize("case", MOVE_CASES)
def test_bad_target_is_refused_and_bob_holds(scene: Scene, case: BadInput) -> None:
    check_rejected(scene, case)
    target = with_value(scene.bob, 0, scene.bob.positions[0] + 0.05)
    move_and_arrive(scene.world, scene.bob, target)
    assert len(scene.commands) == 1


def test_bad_target_mid_motion_leaves_the_motion_going(scene: Scene) -> None:
    world, bob = scene.world, scene.bob
    goal = with_value(bob, 0, bob.positions[0] + 0.5)
    bob.move_to(goal)
    world.run(0.2)
    assert bob.is_moving
    before = take_snapshot(scene)
    with pytest.raises(JointLimitError):
        bob.move_to(just_above_upper(bob, JOINT4))
    assert_untouched(before, take_snapshot(scene))
    assert len(scene.commands) == 1  # only the good one
    deadline = world.time + 5.0
    while bob.is_moving and world.time < deadline:
        world.run(0.05)
    world.run(HOLD_CHECK_S)
    assert np.abs(bob.positions - goal).max() < ARRIVAL_RAD


def test_bad_command_on_the_topic_is_logged_and_ignored(
    scene: Scene, caplog: pytest.LogCaptureFixture
) -> None:
    """A command published straight on the bus cannot raise to its sender; it is logged."""
    world, bob = scene.world, scene.bob
    before = take_snapshot(scene)
    bad = list(bob.positions)
    bad[1] = math.nan
    with caplog.at_level(logging.WARNING, logger="armfleet"):
        world.bus.publish("/bob/position_controller/commands", JointCommand(tuple(bad)))
    assert any(
        "rejected command" in r.message and bob.joint_names[1] in r.message for r in caplog.records
    )
    assert_untouched(before, take_snapshot(scene))
    world.run(HOLD_CHECK_S)
    assert np.abs(bob.positions - before.positions).max() < HOLD_DRIFT_RAD


def test_refused_spawn_leaves_no_topics_behind(scene: Scene) -> None:
    topics = scene.world.bus.topics
    with pytest.raises(ParameterError):
        scene.world.spawn("toby", parameters={"position_controller": {"kp_s2": -1.0}})
    assert scene.world.bus.topics == topics


@pytest.fixture
def two_worlds() -> Iterator[tuple[armfleet.World, armfleet.World]]:
    first, second = armfleet.World(), armfleet.World()
    try:
        yield first, second
    finally:
        first.close()
        second.close()


def test_bad_spawn_in_one_world_does_not_reach_another(
    two_worlds: tuple[armfleet.World, armfleet.World],
) -> None:
    first, second = two_worlds
    second.spawn("bob")
    bodies = p.getNumBodies(physicsClientId=second.physics_client)
    with pytest.raises(UnknownModel):
        first.spawn("bob", model="pand")
    assert list(second.arms) == ["bob"] and second.time > 0.0
    assert p.getNumBodies(physicsClientId=second.physics_client) == bodies
    first.spawn("bob")  # the name is free in the first world
