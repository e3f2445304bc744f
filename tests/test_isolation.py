"""Invariant 5: two worlds in one process share nothing; invariant 2: commands stay in their arm."""

from __future__ import annotations

import numpy as np
import pybullet as p

import armfleet


def test_two_worlds_are_independent() -> None:
    first, second = armfleet.World(), armfleet.World(dt=0.002)
    try:
        assert first.physics_client != second.physics_client
        bob_1 = first.spawn("bob")
        bob_2 = second.spawn("bob", at=(0.5, 0.5, 0, 45))  # same name: another world
        second_before = bob_2.positions
        second_time = second.time
        heard_in_second: list[object] = []
        second.bus.subscribe("/bob/position_controller/commands", heard_in_second.append)

        bob_1.move_to(bob_1.positions + 0.3)
        first.run(1.5)
        assert np.abs(bob_1.positions - (np.array(bob_1.description.home) + 0.3)).max() < 1e-3
        assert second.time == second_time
        assert heard_in_second == []
        assert np.abs(bob_2.positions - second_before).max() == 0.0
        assert p.getNumBodies(physicsClientId=first.physics_client) == 2  # ground + bob
        assert second.dt == 0.002 and first.dt == 0.001

        first.close()
        second.run(0.1)  # unaffected by the other world's closing
        assert second.tf.lookup("world", "bob_base_link")[0, 3] == 0.5
    finally:
        first.close()
        second.close()


def test_command_to_one_arm_moves_that_arm_only(pair: armfleet.World) -> None:
    bob, toby = pair.arm("bob"), pair.arm("toby")
    toby_before = toby.positions
    bob.move_to(bob.positions - 0.4)
    assert bob.is_moving and not toby.is_moving
    pair.run(2.0)
    assert np.abs(toby.positions - toby_before).max() < 1e-5


def test_closed_world_refuses_use() -> None:
    world = armfleet.World()
    world.close()
    try:
        world.step()
    except armfleet.ArmfleetError as exc:
        assert "closed" in str(exc)
    else:
        raise AssertionError("a closed world must refuse to step")
