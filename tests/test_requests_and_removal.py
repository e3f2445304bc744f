"""Requests from other threads run at step boundaries, in order; arms can leave the world."""

from __future__ import annotations

import threading

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.description import ModelLibrary
from armfleet.messages import BringupEvent, TFMessage

#: How an unknown-model error lists the choices: every model in description/.
AVAILABLE_MODELS = "available: " + ", ".join(ModelLibrary().names)


def test_concurrent_spawn_requests_are_queued_not_interleaved(world: armfleet.World) -> None:
    """Eight clients ask for an arm at once: bring-ups never interleave."""
    events: list[BringupEvent] = []
    world.bus.subscribe("/bringup", events.append)
    barrier = threading.Barrier(8)
    futures = []
    lock = threading.Lock()

    def client(index: int) -> None:
        barrier.wait()
        future = world.submit(lambda: world.spawn(f"arm{index}", at=(index * 1.0, 0)))
        with lock:
            futures.append(future)

    threads = [threading.Thread(target=client, args=(i,)) for i in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    while not all(f.done() for f in futures):
        world.step()
    assert sorted(f.result().name for f in futures) == [f"arm{i}" for i in range(8)]
    order = [e.arm for e in events]
    # Each arm's four stages are contiguous: no arm starts before the previous is ready.
    assert all(order[i : i + 4] == [order[i]] * 4 for i in range(0, len(order), 4))
    assert len(set(order)) == 8


def test_a_failing_request_reports_to_its_caller_only(world: armfleet.World) -> None:
    bad = world.submit(lambda: world.spawn("bob", model="nope"))
    good = world.submit(lambda: world.spawn("bob"))
    world.step()
    with pytest.raises(armfleet.ArmfleetError, match=AVAILABLE_MODELS):
        bad.result(timeout=0)
    assert good.result(timeout=0).name == "bob"


def test_requests_pending_at_close_fail_cleanly() -> None:
    world = armfleet.World()
    pending = world.submit(lambda: world.spawn("bob"))
    world.close()
    with pytest.raises(armfleet.ArmfleetError, match="closed"):
        pending.result(timeout=1)


def test_removed_arm_leaves_no_trace_and_others_keep_going(pair: armfleet.World) -> None:
    bob, toby = pair.arm("bob"), pair.arm("toby")
    bob_controller = bob.position_controller  # the handle's parts raise once bob is gone
    bodies = p.getNumBodies(physicsClientId=pair.physics_client)
    toby_before = toby.positions
    pair.remove("bob")
    assert list(pair.arms) == ["toby"]
    assert p.getNumBodies(physicsClientId=pair.physics_client) == bodies - 1
    children = {t.child_frame_id for m in pair.bus.latched("/tf_static") for t in m.transforms}
    assert "bob_base_link" not in children and "toby_base_link" in children
    with pytest.raises(armfleet.ArmfleetError, match="arms: toby"):
        pair.tf.lookup("world", "bob_tool0")
    # A command on bob's old topic reaches nobody; toby holds.
    pair.bus.publish("/bob/position_controller/commands", armfleet.JointCommand((0.0,) * 7))
    pair.run(0.3)
    assert np.abs(toby.positions - toby_before).max() < 1e-5
    assert not bob_controller.is_moving
    # The name is free again.
    again = pair.spawn("bob", at=(0, 1))
    assert again.pose.y == 1.0


def test_tap_sees_every_topic(pair: armfleet.World) -> None:
    seen: set[str] = set()
    tap = pair.bus.subscribe_all(lambda topic, message: seen.add(topic))
    pair.run(0.01)
    assert {"/bob/joint_states", "/toby/joint_states", "/tf"} <= seen
    tap.cancel()
    seen.clear()
    pair.run(0.01)
    assert seen == set()
    static: list[TFMessage] = pair.bus.latched("/tf_static")
    assert len(static) == 2
