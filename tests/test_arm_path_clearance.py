"""Issue #28 item 4: an object is not added into the remaining path of a moving arm.

A Panda at home turns its first joint by 1.2 rad. Its first joint's axis is the
world's z through its base, so its hand sweeps an arc about that axis: the hand's
position half-way is the home position turned by 0.6 rad about z (an independent
computation, no planner). A box there is refused while the arm moves, the arm reaches
its target untouched, and the world steps on exactly as a world where nothing was
asked. Without the check, the same box is added and the arm hits it (shown by the
physics: a protective stop short of the target).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.messages import ArmMode
from armfleet.objects.arm_path_clearance import PATH_CLEARANCE_M, ObjectInArmPath

TURN_RAD = 1.2
BOX_M = 0.05
#: Steps after the move starts when the object is added (the arm is under way).
STEPS_BEFORE_ADD = 5
#: Steps that let the arm finish its motion and settle [1 ms each].
STEPS_TO_FINISH = 3000
#: An arm holding its target tracks it within this [rad].
HOLD_TOLERANCE_RAD = 2e-3
#: How far the executed motion may stray from its reference where the check is asked [m]:
#: a Panda tracks its reference within about 1e-3 rad, a few mm at its hand.
TRACKING_SLACK_M = 0.01


def turned_about_z(point: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    turned: np.ndarray = rotation @ point
    return turned


def start_turn(world: armfleet.World) -> tuple[np.ndarray, np.ndarray]:
    """bob turning its first joint by TURN_RAD; returns its target and the hand's
    position half-way along the turn [m]."""
    bob = world.spawn("bob")
    hand = world.tf.lookup("world", "bob_panda_hand")[:3, 3]
    target = bob.positions.copy()
    target[0] += TURN_RAD
    bob.move_to(target)
    for _ in range(STEPS_BEFORE_ADD):
        world.step()
    assert bob.is_moving
    return target, turned_about_z(hand, TURN_RAD / 2)


@pytest.fixture
def second_world() -> Iterator[armfleet.World]:
    with armfleet.World() as world:
        yield world


def test_a_box_in_a_moving_arms_path_is_refused_naming_the_arm(
    world: armfleet.World, second_world: armfleet.World
) -> None:
    target, half_way = start_turn(world)
    start_turn(second_world)  # the same motion, where nothing is asked
    with pytest.raises(ObjectInArmPath) as refused:
        world.add_object("crate", "box", size=[BOX_M] * 3, mass=0.0, at=tuple(half_way))
    error = refused.value
    message = str(error)
    assert "\n" not in message
    assert "in the path of arm bob, which is moving" in message, message
    assert error.arm == "bob"
    assert error.distance_m < 0  # through the box, not past it
    assert 0.0 < error.after_s < 3.0
    assert "crate" not in world.objects
    # The arm's body was posed along its path for the check, and set back exactly: the
    # world steps on bit for bit as the one where nothing was asked, and bob arrives.
    bob, twin = world.arm("bob"), second_world.arm("bob")
    for _ in range(STEPS_TO_FINISH):
        world.step()
        second_world.step()
    assert np.array_equal(bob.positions, twin.positions)
    assert np.array_equal(bob.joint_state.velocity, twin.joint_state.velocity)
    assert bob.mode is ArmMode.HOLDING
    assert np.abs(bob.positions - target).max() < HOLD_TOLERANCE_RAD


def test_without_the_check_the_arm_would_hit_the_box(world: armfleet.World) -> None:
    """The refusal is not overcautious: the same box, added while bob stands still (so
    nothing refuses it), stops bob when its motion back home goes through it."""
    bob = world.spawn("bob")
    hand = world.tf.lookup("world", "bob_panda_hand")[:3, 3]
    home = bob.positions.copy()
    # Box at the half-way point, added while bob stands still away from it (turned
    # 1.2 rad): bob's path back home then goes through it.
    target = home.copy()
    target[0] += TURN_RAD
    bob.move_to(target)
    for _ in range(STEPS_TO_FINISH):
        world.step()
    assert not bob.is_moving
    world.add_object(
        "crate", "box", size=[BOX_M] * 3, mass=0.0, at=tuple(turned_about_z(hand, TURN_RAD / 2))
    )
    bob.move_to(home)
    for _ in range(STEPS_TO_FINISH):
        world.step()
    assert bob.mode is ArmMode.PROTECTIVE_STOP
    assert np.abs(bob.positions - home).max() > 0.1


def test_a_box_clear_of_the_path_is_added_while_the_arm_moves(world: armfleet.World) -> None:
    _, half_way = start_turn(world)
    # The same box on the other side of the base, where the turn never goes.
    away = turned_about_z(half_way, np.pi)
    world.add_object("crate", "box", size=[BOX_M] * 3, mass=0.0, at=tuple(away))
    assert "crate" in world.objects
    bob = world.arm("bob")
    for _ in range(STEPS_TO_FINISH):
        world.step()
    assert bob.mode is ArmMode.HOLDING


def test_a_box_beside_the_path_keeps_its_clearance(world: armfleet.World) -> None:
    _, half_way = start_turn(world)
    # Below the hand, far enough under the path's lowest point to be clear...
    low = half_way.copy()
    low[2] = BOX_M / 2  # resting on the floor, 0.5 m under the hand's arc
    world.add_object("floor_box", "box", size=[BOX_M] * 3, mass=0.0, at=tuple(low))
    # ...and the refusal names a clearance no smaller than the path's.
    with pytest.raises(ObjectInArmPath) as refused:
        world.add_object("crate", "sphere", size=BOX_M / 2, mass=0.3, at=tuple(half_way))
    assert refused.value.distance_m < PATH_CLEARANCE_M


def test_refusals_agree_with_the_motion_the_physics_executes(
    world: armfleet.World, second_world: armfleet.World
) -> None:
    """Spheres on the hand's arc and ever farther from it: those the arm's executed motion
    (in a twin world with no object, measured every step by PyBullet against the sphere's
    shape) comes into are refused, those it stays well clear of are added."""
    radius = 0.02
    offsets = (0.0, 0.04, 0.08, 0.12, 0.2, 0.3)  # outwards from the hand's arc [m]
    start_turn(world)
    _, half_way = start_turn(second_world)
    outward = np.array([half_way[0], half_way[1], 0.0]) / np.hypot(half_way[0], half_way[1])
    centres = [half_way + offset * outward for offset in offsets]
    client = second_world.physics_client
    shape = p.createCollisionShape(p.GEOM_SPHERE, radius=radius, physicsClientId=client)
    twin = second_world.arm("bob")
    closest = [np.inf] * len(centres)
    while twin.is_moving:
        second_world.step()
        for index, centre in enumerate(centres):
            points = p.getClosestPoints(
                twin.body.body_id, -1, 0.5, collisionShapeB=shape,
                collisionShapePositionB=centre.tolist(), physicsClientId=client,
            )  # fmt: skip
            for point in points:
                closest[index] = min(closest[index], point[8])
    assert closest[0] < 0 < closest[-1] - 0.05  # the test spans both outcomes
    for index, (centre, distance) in enumerate(zip(centres, closest, strict=True)):
        try:
            world.add_object(f"ball{index}", "sphere", size=radius, mass=0.0, at=tuple(centre))
            added = True
        except ObjectInArmPath:
            added = False
        if distance < PATH_CLEARANCE_M / 2:
            assert not added, (offsets[index], distance)
        if distance > PATH_CLEARANCE_M + TRACKING_SLACK_M:
            assert added, (offsets[index], distance)
