"""Invariant 3: arms come up strictly one at a time, each ready before the next starts."""

from __future__ import annotations

import numpy as np

import armfleet
from armfleet.messages import BringupEvent, BringupStage

STAGES = list(BringupStage)


def test_stages_are_strictly_ordered(world: armfleet.World) -> None:
    events: list[BringupEvent] = []
    world.bus.subscribe("/bringup", events.append)
    for name, x in (("bob", 0.0), ("toby", 1.0), ("carol", 2.0)):
        world.spawn(name, at=(x, 0))
    assert [(e.arm, e.stage) for e in events] == [
        (arm, stage) for arm in ("bob", "toby", "carol") for stage in STAGES
    ]
    stamps = [e.stamp for e in events]
    assert stamps == sorted(stamps)
    # Every stage of bob happens before the first stage of toby, also in simulated time.
    last_bob = max(e.stamp for e in events if e.arm == "bob")
    first_toby = min(e.stamp for e in events if e.arm == "toby")
    assert last_bob <= first_toby


def test_ready_means_joint_states_flow_and_pose_is_held(world: armfleet.World) -> None:
    bob = world.spawn("bob")
    home = np.array(bob.description.home)
    assert bob.joint_state.stamp <= world.time
    assert np.abs(bob.positions - home).max() < 1e-3
    assert bob.position_controller.is_holding
    world.run(1.0)  # holds under gravity with no command
    assert np.abs(bob.positions - home).max() < 1e-4


def test_bringup_of_a_later_arm_does_not_disturb_a_running_one(world: armfleet.World) -> None:
    bob = world.spawn("bob")
    before = bob.positions
    world.spawn("toby", at=(1, 0))
    assert np.abs(bob.positions - before).max() < 1e-5


def test_arm_is_not_listed_until_spawned_and_initial_positions_apply(
    world: armfleet.World,
) -> None:
    assert world.arms == {}
    start = [0.1, -0.5, 0.2, -2.0, 0.1, 1.8, 0.5]
    bob = world.spawn("bob", initial_positions=start)
    assert list(world.arms) == ["bob"]
    assert np.abs(bob.positions - start).max() < 1e-3
