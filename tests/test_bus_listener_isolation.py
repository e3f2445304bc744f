"""Issue #14 item 2: a subscriber that raises never stops the arm it listens to.

A passive listener's failure is logged once with its topic and callback, counted
in ``Bus.failures`` and the listener dropped; the publisher (the joint-state
broadcaster inside a controller update) never sees it, so the arm finishes its
motion. Only a subscriber that owns its failures (a controller's own command
subscription, ``on_error=controller.fail``) puts its arm in ``error``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armfleet
from armfleet.controllers import Controller
from armfleet.controllers.parameters import ParameterSpec
from armfleet.messages import JointCommand, JointState

#: A finished move ends within the controller's holding tolerance of its target [rad].
ARRIVAL_RAD = 1e-3
#: Joint-space distance of the test move per joint [rad]: ~1 s of motion for a Panda.
MOVE_RAD = 0.4


class Listener:
    """A passive listener with a bug: it raises on its ``fail_at``-th message."""

    def __init__(self, fail_at: int) -> None:
        self.calls = 0
        self.fail_at = fail_at

    def on_message(self, _message: Any) -> None:
        self.calls += 1
        if self.calls == self.fail_at:
            _ = 1 / 0

    def on_any(self, _topic: str, message: Any) -> None:
        self.on_message(message)


def move_and_break(
    world: armfleet.World, subscribe: Callable[[Listener], object]
) -> tuple[armfleet.Arm, np.ndarray, Listener]:
    """Start a move of bob, let the listener fail mid-motion, run until he is done."""
    bob = world.arm("bob")
    target = bob.positions + MOVE_RAD * np.array([1, -1, 1, 1, 1, -1, 1])
    duration = bob.move_to(target)
    listener = Listener(fail_at=round(0.3 * duration / world.dt))  # a third of the way
    subscribe(listener)
    world.run(duration + 0.5)
    return bob, target, listener


@pytest.mark.parametrize(
    "rate_hz",
    [
        pytest.param(1000.0, id="broadcaster at the step rate -> the fleet-wide path"),
        pytest.param(500.0, id="broadcaster at half the rate -> the arm's own manager"),
    ],
)
def test_a_raising_joint_state_subscriber_is_dropped_and_the_arm_finishes_its_move(
    world: armfleet.World, rate_hz: float, caplog: pytest.LogCaptureFixture
) -> None:
    world.spawn("bob", parameters={"joint_state_broadcaster": {"publish_rate_hz": rate_hz}})
    subscriptions = []

    def subscribe(listener: Listener) -> None:
        subscriptions.append(world.bus.subscribe("/bob/joint_states", listener.on_message))

    with caplog.at_level(logging.ERROR, logger="armfleet"):
        bob, target, listener = move_and_break(world, subscribe)
    # The arm never noticed: no fault, target reached, broadcaster still publishing.
    assert bob.controller_manager.fault is None
    assert np.abs(bob.positions - target).max() < ARRIVAL_RAD
    states: list[JointState] = []
    world.bus.subscribe("/bob/joint_states", states.append)
    world.step()
    world.step()
    assert states, "the broadcaster stopped publishing"
    # The listener was dropped at its failure: called exactly fail_at times.
    assert listener.calls == listener.fail_at
    assert not subscriptions[0].active
    (failure,) = world.bus.failures
    assert failure.topic == "/bob/joint_states"
    assert "Listener.on_message" in failure.callback
    assert isinstance(failure.error, ZeroDivisionError)
    assert subscriptions[0].failure is failure
    # Logged once, naming the topic and the callback.
    records = [r for r in caplog.records if "Listener.on_message" in r.getMessage()]
    assert len(records) == 1
    assert "/bob/joint_states" in records[0].getMessage()


def test_a_raising_tap_is_dropped_and_other_subscribers_still_get_every_message(
    world: armfleet.World,
) -> None:
    world.spawn("bob")
    healthy: list[JointState] = []
    world.bus.subscribe("/bob/joint_states", healthy.append)
    taps = []
    bob, target, _ = move_and_break(
        world, lambda listener: taps.append(world.bus.subscribe_all(listener.on_any))
    )
    assert bob.controller_manager.fault is None
    assert np.abs(bob.positions - target).max() < ARRIVAL_RAD
    assert not taps[0].active
    assert [f.topic for f in world.bus.failures] == ["*"]
    # The healthy subscriber after the faulty one saw every step's state, with no gap.
    stamps = np.array([s.stamp for s in healthy])
    assert np.allclose(np.diff(stamps), world.dt)


def test_a_subscriber_failing_on_a_latched_replay_is_dropped_not_raised(
    world: armfleet.World,
) -> None:
    world.spawn("bob")
    listener = Listener(fail_at=1)
    subscription = world.bus.subscribe("/tf_static", listener.on_message)
    assert not subscription.active
    assert listener.calls == 1
    assert [f.topic for f in world.bus.failures] == ["/tf_static"]


class CommandedController(Controller):
    """A controller of bob whose own command subscription has a bug (it divides by zero)."""

    type_name = "buggy_controller"
    rate_parameter = "rate_hz"
    parameter_schema = (ParameterSpec("rate_hz", 100.0, "update rate [Hz]", 1.0, 1000.0),)

    def on_configure(self) -> None:
        topic = self.arm.topic("buggy_controller/commands")
        self.arm.bus.advertise(topic, JointCommand)
        self._subscription = self.arm.bus.subscribe(topic, self._on_command, on_error=self.fail)

    def _on_command(self, command: JointCommand) -> None:
        self.gain = 1 / len(command.positions[7:])  # the bug: no 8th value, ZeroDivisionError

    def update(self, stamp: float) -> None:
        pass


def test_a_controller_s_own_command_subscription_failing_puts_its_arm_in_error(
    world: armfleet.World, tmp_path: Path
) -> None:
    """The internal case: the controller owns the failure, so the arm faults (brakes on)
    and the publisher still does not see the exception."""
    bob = world.spawn("bob")
    toby = world.spawn("toby", at=(1, 0))
    parameters = tmp_path / "buggy_controller.yaml"
    parameters.write_text("buggy_controller:\n  rate_hz: 100.0\n")
    controller = CommandedController(bob.position_controller.arm, parameters)
    bob.controller_manager.load(controller)
    bob.controller_manager.activate(controller.name)
    world.bus.publish("/bob/buggy_controller/commands", JointCommand((0.0,) * 7))
    reason = "buggy_controller raised ZeroDivisionError: division by zero"
    assert bob.controller_manager.fault == reason
    assert toby.controller_manager.fault is None  # only this arm
    assert not world.bus.failures  # not dropped as a listener: its owner handled it
    before = bob.positions
    world.run(0.2)
    assert np.abs(bob.positions - before).max() < ARRIVAL_RAD  # brakes hold it


def test_the_controllers_command_subscriptions_are_the_ones_that_own_their_failures(
    world: armfleet.World,
) -> None:
    """Which subscribers are internal, derived from the bus rather than listed by hand:
    exactly the command topics of bob's command-writing controllers."""
    bob = world.spawn("bob")
    owning = {
        topic
        for topic, subscriptions in world.bus._subscriptions.items()
        for s in subscriptions
        if s.on_error is not None
    }
    assert owning == {"/bob/position_controller/commands", "/bob/gripper_controller/commands"}
    writers = {c.name for c in bob.controller_manager.controllers.values() if c.writes_commands}
    assert {t.split("/")[2] for t in owning} == writers
