"""The learning environments against their libraries' own checkers, random rollouts, bad
actions, determinism, vectorizing, rendering and clean-up (armfleet.envs).

The physics of the actions and the tasks' rewards are in tests/test_envs_tasks.py.
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import json
import math
import re
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pybullet as p
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

from armfleet.envs import (
    HANDOVER_ID,
    REACH_ID,
    SCENE_ID,
    ActionKind,
    HandoverEnv,
    HandoverTask,
    InvalidAction,
    InvalidOption,
    MultiArmEnv,
    MultiArmParallelEnv,
    ReachEnv,
    ReachTask,
)

ROOT = Path(__file__).resolve().parents[1]
#: Environment steps of the random rollouts.
ROLLOUT_STEPS = 1000


def random_rollout(env: MultiArmEnv, steps: int, seed: int, nan_in: tuple[str, str]) -> float:
    """``steps`` random actions, resetting when an episode ends; every observation must lie
    in the observation space and every reward be finite. Halfway, an action with a NaN in
    ``nan_in`` (arm, entry) must be refused with nothing changed. Returns the simulated
    time of the last episode [s]."""
    env.action_space.seed(seed)
    observation, _ = env.reset(seed=seed)
    for index in range(steps):
        if index == steps // 2:
            assert_nan_refused(env, env.step, env.action_space.sample(), *nan_in)
        observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert observation in env.observation_space
        assert math.isfinite(float(reward))
        assert set(info) >= {"success", "stopped", "refused", "clipped", "time_s"}
        if terminated or truncated:
            observation, _ = env.reset()
    return env.world.time


def state(env: MultiArmEnv) -> list[Any]:
    """Time, every joint, every object's pose and every arm's targets."""
    world = env.world
    return [
        world.time,
        [arm.body.position.copy() for arm in world.arms.values()],
        [arm.body.velocity.copy() for arm in world.arms.values()],
        [obj.pose for obj in world.objects.values()],
        [env.commander(name).target for name in env.arm_names],
        [env.commander(name).tool_target for name in env.arm_names],
    ]


def assert_nan_refused(
    env: MultiArmEnv, step: Callable[[Any], object], action: Any, arm: str, entry: str
) -> None:
    """A NaN in ``action[arm][entry]`` raises one line naming them and what is valid, and
    leaves the episode as it was."""
    before = state(env)
    action[arm][entry][0] = np.nan
    with pytest.raises(InvalidAction) as refused:
        step(action)
    message = str(refused.value)
    assert isinstance(refused.value, armfleet.ArmfleetError)
    assert (refused.value.arm, refused.value.field) == (arm, entry)
    assert "\n" not in message and f"action[{arm!r}][{entry!r}]: element 0 is nan" in message
    assert "valid: " in message and "finite numbers in [" in message
    assert gym.utils.env_checker.data_equivalence(state(env), before, exact=True)


@pytest.fixture(scope="module")
def reach() -> Iterator[MultiArmEnv]:
    env = ReachEnv(arm_count=2, control_period=2)
    yield env
    env.close()


def test_gymnasium_checker_passes_reach_and_handover() -> None:
    for env_id in (REACH_ID, HANDOVER_ID):
        env = gym.make(env_id, control_period=5)
        check_env(env.unwrapped)  # raises on any failure; renders both modes via the spec
        env.close()


def test_pettingzoo_checker_passes_with_one_agent_per_arm() -> None:
    env = MultiArmParallelEnv(HandoverTask(), control_period=2, action_kind="joint_deltas")
    assert env.possible_agents == ["bob", "toby"]
    # Two episodes of up to 1,000 cycles each, random actions for every live agent.
    parallel_api_test(env, num_cycles=ROLLOUT_STEPS)
    assert env.observation_space("bob") is env.env.arm_observation_space("bob")
    observations, _ = env.reset(seed=3)
    state = env.state()  # every arm's observation in one vector
    assert state in env.state_space
    bob = np.asarray(gym.spaces.flatten(env.observation_space("bob"), observations["bob"]))
    np.testing.assert_array_equal(state[: bob.size], bob)
    assert env.action_space("toby").contains(env.action_space("toby").sample())
    env.close()


def test_a_thousand_random_reach_steps_run(reach: MultiArmEnv) -> None:
    assert random_rollout(reach, ROLLOUT_STEPS, seed=4, nan_in=("arm1", "joint_deltas")) > 0


def test_a_thousand_random_handover_steps_run() -> None:
    env = HandoverEnv(control_period=2)  # tool-delta actions: IK every step
    assert random_rollout(env, ROLLOUT_STEPS, seed=5, nan_in=("toby", "gripper")) > 0
    env.close()


def test_a_thousand_random_parallel_steps_run() -> None:
    env = MultiArmParallelEnv(ReachTask(3), control_period=2, max_cycles=300)
    observations, infos = env.reset(seed=6)
    assert set(observations) == set(infos) == {"arm0", "arm1", "arm2"}
    for agent in env.possible_agents:
        env.action_space(agent).seed(6)
    episodes = 0
    for index in range(ROLLOUT_STEPS):
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        if index == ROLLOUT_STEPS // 2:
            spoilt = {agent: env.action_space(agent).sample() for agent in env.agents}
            assert_nan_refused(env.env, env.step, spoilt, "arm2", "joint_deltas")
            assert env.agents == env.possible_agents  # nobody was dropped
        observations, rewards, terminated, truncated, _ = env.step(actions)
        for agent, observation in observations.items():
            assert env.observation_space(agent).contains(observation)
        assert len(set(rewards.values())) == 1  # the team shares the reward
        if not env.agents:
            assert all(terminated.values()) or all(truncated.values())
            episodes += 1
            env.reset()
    assert episodes >= ROLLOUT_STEPS // 300  # truncated at max_cycles at the latest
    env.close()


def test_a_nan_action_is_refused_in_one_line_and_the_episode_goes_on(
    reach: MultiArmEnv,
) -> None:
    reach.reset(seed=1)
    reach.step(reach.action_space.sample())
    before = reach.world.time
    assert_nan_refused(reach, reach.step, reach.action_space.sample(), "arm1", "joint_deltas")
    reach.step(reach.action_space.sample())
    assert reach.world.time > before


@pytest.mark.parametrize(
    ("action", "words"),
    [
        ({"arm0": None}, ["a dict with one entry per arm", "arm0", "arm1"]),
        ("go", ["got str", "one entry per arm"]),
        ({"arm0": {}, "arm1": {}}, ["action['arm0']", "'joint_deltas'"]),
    ],
)
def test_a_malformed_action_names_what_is_valid(
    reach: MultiArmEnv, action: object, words: list[str]
) -> None:
    reach.reset(seed=1)
    with pytest.raises(InvalidAction) as refused:
        reach.step(action)  # type: ignore[arg-type]
    for word in words:
        assert word in str(refused.value)


def test_wrong_shapes_and_types_are_refused_out_of_box_values_clipped(
    reach: MultiArmEnv,
) -> None:
    reach.reset(seed=1)
    good = reach.action_space.sample()
    for bad, problem in (
        (np.zeros(6), "shape (6,)"),
        (np.array(["a"] * 7), "<U1 values"),
        (np.array([True] * 7), "bool values"),
        ([0.0, 0.0, math.inf, 0, 0, 0, 0], "element 2 is inf"),
    ):
        action = {**good, "arm0": {**good["arm0"], "joint_deltas": bad}}
        with pytest.raises(InvalidAction, match=re.escape(problem)):
            reach.step(action)
    before = reach.commander("arm0").target
    action = {**good, "arm0": {**good["arm0"], "joint_deltas": np.full(7, 5.0)}}
    _, _, _, _, info = reach.step(action)
    assert info["clipped"] == ["arm0.joint_deltas"]
    box = reach.arm_action_space("arm0")["joint_deltas"]
    assert isinstance(box, gym.spaces.Box)
    step = float(box.high[0])  # 0.05 rad
    upper = reach.world.arm("arm0").joint_limits[1]
    np.testing.assert_array_equal(reach.commander("arm0").target, np.minimum(before + step, upper))


def test_options_out_of_their_choices_are_refused_with_the_choices() -> None:
    with pytest.raises(InvalidOption, match="joint_positions, joint_deltas, tool_delta"):
        ReachEnv(arm_count=1, action_kind="joint_velocity")
    with pytest.raises(InvalidOption, match=r"control_period = 0 .* \[1, 10000\]"):
        ReachEnv(arm_count=1, control_period=0)
    with pytest.raises(InvalidOption, match="terminate, reset"):
        ReachEnv(arm_count=1, on_stop="ignore")
    with pytest.raises(InvalidOption, match="None, rgb_array, human"):
        ReachEnv(arm_count=1, render_mode="ansi")
    with pytest.raises(InvalidOption, match="dense, sparse"):
        HandoverEnv(reward="shaped")
    with pytest.raises(InvalidOption, match=r"arm_count = 9 .* \[1, 8\]"):
        ReachTask(9)
    with pytest.raises(InvalidOption, match="a scene with at least one arm"):
        MultiArmEnv(armfleet.FleetSpec())  # nothing to drive (its world is closed again)


def rollout(env: MultiArmEnv, seed: int, steps: int) -> list[Any]:
    observation, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    trace: list[Any] = [observation]
    for _ in range(steps):
        trace.append(env.step(env.action_space.sample())[:4])
    return trace


def test_reset_with_a_seed_repeats_the_episode_exactly(reach: MultiArmEnv) -> None:
    first = rollout(reach, seed=11, steps=100)
    rollout(reach, seed=12, steps=10)  # something else in between
    second = rollout(reach, seed=11, steps=100)
    assert gym.utils.env_checker.data_equivalence(first, second, exact=True)


def test_a_seeded_handover_repeats_exactly_ik_and_grasps_included() -> None:
    env = HandoverEnv(control_period=10, on_stop="reset")  # tool deltas: IK every step
    first = rollout(env, seed=7, steps=60)
    second = rollout(env, seed=7, steps=60)
    other = rollout(env, seed=8, steps=1)
    env.close()
    assert gym.utils.env_checker.data_equivalence(first, second, exact=True)
    bar = [trace[0]["bob"]["objects"]["bar"] for trace in (first, other)]
    assert np.linalg.norm(bar[0][:2] - bar[1][:2]) > 1e-4  # the bar starts elsewhere


def test_different_seeds_draw_different_targets(reach: MultiArmEnv) -> None:
    targets = []
    for seed in range(4):
        observation, _ = reach.reset(seed=seed)
        targets.append(np.concatenate([observation[a]["target_pose"] for a in ("arm0", "arm1")]))
    for i in range(4):
        for j in range(i):
            assert np.linalg.norm(targets[i][:3] - targets[j][:3]) > 1e-3


def test_two_subprocesses_run_the_registered_ids_as_one_process_does() -> None:
    # "spawn": fresh interpreters, which find the id by importing the module it names.
    envs = gym.vector.AsyncVectorEnv(
        [lambda: gym.make(f"armfleet.envs:{REACH_ID}", arm_count=2, control_period=10)] * 2,
        context="spawn",
    )
    observations, _ = envs.reset(seed=[21, 22])
    envs.action_space.seed(0)
    for _ in range(20):
        _, rewards, _, _, infos = envs.step(envs.action_space.sample())
    assert rewards.shape == (2,) and np.all(rewards < 0)
    assert np.all(infos["time_s"] > 0.2)
    envs.close()
    here = ReachEnv(arm_count=2, control_period=10)
    for index, seed in enumerate((21, 22)):
        observation, _ = here.reset(seed=seed)
        for arm in ("arm0", "arm1"):
            np.testing.assert_array_equal(
                observations[arm]["target_pose"][index], observation[arm]["target_pose"]
            )
    here.close()


def test_rgb_array_renders_the_world_and_shows_the_arms_move() -> None:
    env = ReachEnv(arm_count=1, control_period=100, render_mode="rgb_array", render_size=(160, 120))
    env.reset(seed=0)
    first = env.render()
    assert first is not None and first.shape == (120, 160, 3) and first.dtype == np.uint8
    assert len(np.unique(first.reshape(-1, 3), axis=0)) > 10  # a scene, not a blank
    action = {"arm0": {"joint_deltas": np.full(7, 0.05, np.float32)}}
    for _ in range(10):
        env.step(action)
    second = env.render()
    assert second is not None
    assert np.mean(np.any(first != second, axis=2)) > 0.005  # the arm moved in the picture
    env.close()


def test_human_mode_opens_the_viewer_and_any_spec_makes_an_env() -> None:
    env = MultiArmEnv("bob_and_toby", render_mode="human", control_period=5)
    env.reset(seed=0)
    viewer = env.world.viewer
    assert viewer is not None, env.world.viewer_error
    env.step(env.action_space.sample())
    env.reset(seed=1)  # a new world, a new viewer at the same address
    assert env.world.viewer is not None and env.world.viewer.url == viewer.url
    assert env.render() is None
    assert env.arm_names == ["bob", "toby"]
    env.close()
    assert env.world.closed
    env.close()  # again: nothing happens
    plain = gym.make(SCENE_ID, spec="bob_and_toby")
    plain.reset(seed=0)
    assert plain.unwrapped.world.viewer is None  # type: ignore[attr-defined]
    # (bob_and_toby.yaml asks for a viewer; only "human" gets one.) No task: reward 0.
    assert plain.step(plain.action_space.sample())[1:4] == (0.0, False, False)
    plain.close()


def test_resets_leave_no_pybullet_client_or_thread_behind(reach: MultiArmEnv) -> None:
    reach.reset(seed=0)
    probe = p.connect(p.DIRECT)  # PyBullet hands out the lowest free client id
    p.disconnect(probe)
    threads = threading.active_count()
    for seed in range(40):
        reach.reset(seed=seed)
        reach.step(reach.action_space.sample())
    again = p.connect(p.DIRECT)
    p.disconnect(again)
    assert again <= probe  # (lower if an earlier test's client was let go meanwhile)
    assert threading.active_count() <= threads


def test_import_armfleet_does_not_load_the_environments() -> None:
    code = "import sys, armfleet; print('armfleet.envs' in sys.modules, 'gymnasium' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]


def test_every_public_name_resolves() -> None:
    import armfleet.envs

    for name in armfleet.envs.__all__:
        assert getattr(armfleet.envs, name) is not None
    assert ActionKind("tool_delta") is ActionKind.TOOL_DELTA


def test_the_benchmark_short_mode_writes_every_figure(tmp_path: Path) -> None:
    out = tmp_path / "env_overhead.json"
    script = ROOT / "benchmarks" / "env_overhead.py"
    done = subprocess.run(
        [sys.executable, str(script), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = json.loads(out.read_text())["rows"]
    assert [(row["arms"], row["control_period"]) for row in rows] == [(2, 1), (2, 10)]
    for row in rows:
        assert row["env_steps_per_s"] > 0 and row["raw_physics_steps_per_s"] > 0
        assert row["cmd_physics_steps_per_s"] > 0 and row["env_own_ms_per_step"] != 0
        assert row["env_over_raw"] > 0  # a timing: reported, never asserted
    assert "env/raw" in done.stdout
