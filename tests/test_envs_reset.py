"""Resets restore the launched world from a snapshot: the same world object, and episodes
that repeat bit for bit against a freshly built environment, whatever the episodes before
did (protective stops, a bar pushed off its table or held in a gripper, an arm lifted out
of its stop)."""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

from collections.abc import Callable
from typing import Any

import numpy as np
import pybullet as p
import pytest

from armfleet.controllers.position_controller import check_target
from armfleet.envs import HandoverEnv, MultiArmEnv, ReachEnv
from armfleet.errors import JointLimitError, NonFiniteTarget, TargetLengthError, TargetTypeError
from armfleet.scenarios.handover import grasp, lifted
from armfleet.world.world_snapshot import SnapshotStale

#: Steps of each compared episode.
EPISODE_STEPS = 40


def flat(value: Any) -> np.ndarray:
    """Every number of an observation (nested dicts in key order) as float64."""
    if isinstance(value, dict):
        parts = [flat(value[key]) for key in sorted(value)]
        return np.concatenate(parts) if parts else np.zeros(0)
    return np.asarray(value, dtype=np.float64).ravel()


def seeded_episode(env: MultiArmEnv, seed: int) -> list[np.ndarray]:
    """Observations, rewards and terminations of an episode of sampled actions, all
    seeded by ``seed``."""
    env.action_space.seed(seed)
    observation, info = env.reset(seed=seed)
    record = [flat(observation), np.array([info["time_s"]])]
    for _ in range(EPISODE_STEPS):
        observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
        record += [flat(observation), np.array([reward, terminated, truncated, info["time_s"]])]
        if terminated:
            break
    return record


def assert_bit_identical(first: list[np.ndarray], second: list[np.ndarray]) -> None:
    assert len(first) == len(second)
    for index, (a, b) in enumerate(zip(first, second, strict=True)):
        assert a.tobytes() == b.tobytes(), f"entry {index} differs"


def stop_in_the_floor(env: MultiArmEnv, seed: int) -> None:
    """An episode of arm0 leaning into the floor until a protective stop."""
    env.reset(seed=seed)
    arm = env.world.arm("arm0")
    down = arm.positions
    down[1], down[3] = 1.7, -0.1  # the fingers meet the floor
    for _ in range(100):
        action = {name: {key: np.zeros_like(value) for key, value in entry.items()}
                  for name, entry in env.action_space.sample().items()}  # fmt: skip
        step = np.clip(down - env.commander("arm0").target, -0.05, 0.05)
        action["arm0"]["joint_deltas"] = step.astype(np.float32)
        info = env.step(action)[4]
        if info["stopped"]:
            return
    raise AssertionError("arm0 never touched the floor")


def reach_env(on_stop: str = "terminate") -> ReachEnv:
    return ReachEnv(arm_count=1, on_stop=on_stop)


@pytest.mark.parametrize("on_stop", ["terminate", "reset"])
def test_reach_repeats_bit_for_bit_after_stops_and_other_episodes(on_stop: str) -> None:
    used = reach_env(on_stop)
    world = used.world
    stop_in_the_floor(used, seed=1)
    assert world.safety.stops == 1
    if on_stop == "reset":  # lifted out of the stop: new controllers' motions, then more
        for _ in range(20):
            used.step(used.action_space.sample())
    for seed in (11, 12, 13):
        seeded_episode(used, seed)
    replayed = [seeded_episode(used, seed) for seed in (4, 5)]
    assert used.world is world  # restored, not launched anew
    fresh = reach_env(on_stop)
    expected = [seeded_episode(fresh, seed) for seed in (4, 5)]
    for got, wanted in zip(replayed, expected, strict=True):
        assert_bit_identical(got, wanted)
    used.close()
    fresh.close()


def tcp_in_tool0(env: MultiArmEnv, arm: str) -> np.ndarray:
    tf = env.world.tf
    return np.linalg.solve(tf.world_pose(f"{arm}_tool0"), tf.world_pose(f"{arm}_tcp"))


def move_tcp(env: MultiArmEnv, arm: str, tcp: np.ndarray, close: bool, steps: int) -> None:
    """Tool-delta actions of ``arm`` towards ``tcp`` for ``steps`` steps, fingers held."""
    goal = tcp @ np.linalg.inv(tcp_in_tool0(env, arm))
    limits = np.array([0.02] * 3 + [0.1] * 3)
    for _ in range(steps):
        target = env.commander(arm).tool_target
        error = np.zeros(6)
        error[:3] = goal[:3, 3] - target[:3, 3]
        action = {
            name: {
                "tool_delta": (
                    np.clip(error, -limits, limits) if name == arm else np.zeros(6)
                ).astype(np.float32),
                "gripper": np.array([float(close and name == arm)], np.float32),
            }
            for name in env.arm_names
        }
        env.step(action)


def hold_the_bar(env: MultiArmEnv) -> None:
    """bob picks the bar from above and lifts it: it is held when the episode ends."""
    env.reset(seed=2)
    pick = grasp(env.world.object("bar").pose, -1)
    move_tcp(env, "bob", lifted(pick), close=False, steps=40)
    move_tcp(env, "bob", pick, close=False, steps=40)
    move_tcp(env, "bob", pick, close=True, steps=25)
    move_tcp(env, "bob", lifted(pick), close=True, steps=30)
    assert env.world.arm("bob").gripper.holding


def push_the_bar(env: MultiArmEnv) -> None:
    """The bar knocked sideways off its place, still moving when the episode ends."""
    env.reset(seed=3)
    bar = env.world.object("bar")
    start = bar.position
    p.resetBaseVelocity(bar.body_id, [0.8, 0.4, 0.0], [0.0, 0.0, 3.0],
                        physicsClientId=env.world.physics_client)  # fmt: skip
    for _ in range(10):
        env.step(zero_action(env))
    assert np.linalg.norm(bar.position - start) > 0.05


def zero_action(env: MultiArmEnv) -> dict[str, dict[str, np.ndarray]]:
    return {
        name: {"tool_delta": np.zeros(6, np.float32), "gripper": np.zeros(1, np.float32)}
        for name in env.arm_names
    }


@pytest.mark.parametrize("before", [hold_the_bar, push_the_bar], ids=["held", "pushed"])
def test_handover_repeats_bit_for_bit_after_a_held_or_pushed_bar(
    before: Callable[[MultiArmEnv], None],
) -> None:
    used = HandoverEnv()
    before(used)
    replayed = seeded_episode(used, 6)
    assert not used.world.arm("bob").gripper.holding
    fresh = HandoverEnv()
    assert_bit_identical(replayed, seeded_episode(fresh, 6))
    used.close()
    fresh.close()


def test_a_world_changed_by_hand_is_launched_anew_and_still_repeats() -> None:
    used = reach_env()
    used.reset(seed=0)
    first = used.world
    snapshot = first.snapshot()
    first.add_object("crate", "box", size=(0.1, 0.1, 0.1), at=(0.5, -0.8, 0.05))
    with pytest.raises(SnapshotStale, match=r"its objects were \[\], now \['crate'\]") as caught:
        snapshot.restore()
    assert "\n" not in str(caught.value) and "crate" in first.objects  # unchanged
    replayed = seeded_episode(used, 8)  # the crate's world can't be restored: a new one
    assert used.world is not first and first.closed and "crate" not in used.world.objects
    fresh = reach_env()
    assert_bit_identical(replayed, seeded_episode(fresh, 8))
    used.close()
    fresh.close()


def test_a_world_snapshot_is_followed_by_the_same_steps_bit_for_bit() -> None:
    with armfleet.World() as world:
        arm = world.spawn("bob", "panda")
        box = world.add_object("box", "box", size=(0.05,) * 3, at=(0.45, 0.0, 0.025), mass=0.2)
        snapshot = world.snapshot()
        start_time, start_q = world.time, arm.positions

        def sweep() -> list[bytes]:  # the arm swings through the box
            arm.move_to(start_q + np.array([0.0, 0.6, 0.0, 0.4, 0.0, 0.0, 0.0]))
            states = []
            for _ in range(400):
                world.step()
                states.append(arm.positions.tobytes() + box.pose.tobytes())
            return states

        first = sweep()
        assert world.contacts.total_contacts > 0 or world.safety.stops > 0
        seen: list[object] = []
        world.bus.subscribe("/bob/joint_states", seen.append)
        snapshot.restore()
        assert world.time == start_time and np.array_equal(arm.positions, start_q)
        assert world.safety.stops == 0 and world.contacts.total_contacts == 0
        assert sweep() == first
        assert seen == []  # subscribed after the snapshot: gone with the restore


@pytest.mark.parametrize(
    ("target", "error"),
    [
        ([0.1] * 6 + [float("nan")], NonFiniteTarget),
        ([0.1] * 6 + [3.5], JointLimitError),
        ([0.1] * 6 + [True], TargetTypeError),
        ([0.1] * 6, TargetLengthError),
    ],
)
def test_a_plain_float_list_target_is_checked_as_an_array_is(
    target: list[float], error: type[Exception]
) -> None:
    # The arms' own commands carry lists of floats, checked by a shortcut (a step's cost):
    # the same list as an array (or a tuple) is refused with the same error.
    names = [f"j{i}" for i in range(7)]
    lower, upper = np.full(7, -2.9), np.full(7, 2.9)
    for form in (target, tuple(target), np.array(target, dtype=object)):
        with pytest.raises(error):
            check_target("bob", form, names, lower, upper)
    fine = [0.1] * 7
    assert np.array_equal(check_target("bob", fine, names, lower, upper), np.full(7, 0.1))
