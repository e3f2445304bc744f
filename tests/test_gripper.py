"""gripper_controller: widths, closing on nothing, and holding a box while the arm moves fast."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

import armfleet
from armfleet.errors import GripperCommandError, NoGripper
from armfleet.messages import GripperMode, GripperState

BOX_SIDE_M = 0.04
BOX_MASS_KG = 0.2


def tcp_position(world: armfleet.World, arm: str) -> np.ndarray:
    return world.tf.lookup("world", f"{arm}_panda_hand_tcp")[:3, 3]


@pytest.fixture
def world() -> Iterator[armfleet.World]:
    with armfleet.World() as world:
        world.spawn("bob", "panda")
        yield world


def put_box_between_fingers(world: armfleet.World) -> None:
    """A box on a static pedestal, centred between bob's open finger pads."""
    tcp = tcp_position(world, "bob")
    top = tcp[2] - BOX_SIDE_M / 2
    world.add_object("pedestal", "box", size=(0.08, 0.08, top), mass=0.0, at=(*tcp[:2], top / 2))
    world.add_object(
        "box", "box", size=(BOX_SIDE_M,) * 3, mass=BOX_MASS_KG, at=(*tcp[:2], top + BOX_SIDE_M / 2)
    )


def test_widths_are_reached_within_the_finger_limits(world: armfleet.World) -> None:
    gripper = world.arm("bob").gripper
    assert gripper.max_width == pytest.approx(0.08)
    for width in (0.08, 0.03, 0.055):
        gripper.move_to(width)
        assert gripper.is_moving
        world.run(0.8)
        assert gripper.mode is GripperMode.AT_WIDTH
        assert abs(gripper.width - width) < 2e-4  # 0.2 mm
        velocities = world.arm("bob").joint_state.velocity[-2:]
        assert np.all(np.abs(velocities) < 1e-3)


def test_closing_on_nothing_reports_closed_and_not_holding(world: armfleet.World) -> None:
    gripper = world.arm("bob").gripper
    gripper.open()
    world.run(0.8)
    states: list[GripperState] = []
    world.bus.subscribe("/bob/gripper_controller/state", states.append)
    gripper.close()
    world.run(1.0)
    assert gripper.mode is GripperMode.CLOSED
    assert gripper.width < 0.002
    assert not gripper.holding
    assert states and not any(state.holding for state in states)
    assert states[-1].mode is GripperMode.CLOSED
    assert world.arm("bob").mode is armfleet.ArmMode.HOLDING  # the fingers meeting is no contact


def test_holds_a_box_against_gravity_while_the_arm_moves_at_full_speed(
    world: armfleet.World,
) -> None:
    bob = world.arm("bob")
    gripper = bob.gripper
    gripper.open()
    world.run(0.8)
    put_box_between_fingers(world)
    world.run(0.2)
    gripper.close(force=20.0)
    world.run(0.6)
    assert gripper.mode is GripperMode.SQUEEZING
    assert gripper.holding
    assert gripper.width == pytest.approx(BOX_SIDE_M, abs=5e-4)
    assert gripper.force == pytest.approx(20.0)

    # Lift clear of the pedestal, then swing between two poses at full speed for 2 s.
    home = bob.positions
    lifted = home + np.array([0.0, -0.35, 0.0, 0.35, 0.0, 0.0, 0.0])
    swung = lifted + np.array([1.2, 0.3, -0.8, 0.3, 1.0, 0.5, -1.2])
    bob.move_to(lifted)
    world.run(1.0)
    box = world.object("box")
    offsets: list[float] = []
    peak_speed = 0.0

    def watch(world: armfleet.World) -> None:
        nonlocal peak_speed
        offsets.append(float(np.linalg.norm(box.position - tcp_position(world, "bob"))))
        ratio = np.abs(bob.joint_state.velocity[:7]) / bob.position_controller.max_velocity
        peak_speed = max(peak_speed, float(ratio.max()))

    for target in (swung, lifted, swung):
        bob.move_to(target)
        world.run(0.7, on_step=watch)
    assert len(offsets) >= 2000  # 2 s of motion
    assert peak_speed > 0.9  # some joint ran at (nearly) its velocity limit
    assert max(offsets) < 0.005  # the box stayed between the pads (5 mm)
    assert gripper.holding
    assert bob.mode is not armfleet.ArmMode.PROTECTIVE_STOP  # the held box stops nothing

    gripper.open()
    world.run(1.0)
    assert not gripper.holding
    assert box.position[2] < 0.05  # released: it fell to the floor


def test_bad_gripper_commands_are_refused_and_change_nothing(world: armfleet.World) -> None:
    gripper = world.arm("bob").gripper
    gripper.move_to(0.05)
    world.run(0.6)
    for width, force in ((0.2, None), (-0.01, None), (float("nan"), None)):
        with pytest.raises(GripperCommandError) as raised:
            gripper.move_to(width, force=force)
        assert "give a value in" in str(raised.value)
    for force in (0.0, 1e6, float("inf")):
        with pytest.raises(GripperCommandError) as raised:
            gripper.close(force=force)
        assert "give a value in" in str(raised.value)
    world.run(0.3)
    assert gripper.width == pytest.approx(0.05, abs=2e-4)


def test_models_without_fingers_have_no_gripper() -> None:
    with armfleet.World() as world:
        arm = world.spawn("ur", "ur5")
        assert not arm.has_gripper
        assert "gripper_controller" not in arm.controller_manager.controllers
        with pytest.raises(NoGripper, match="ur5"):
            _ = arm.gripper
