"""What an outside user of the environments met (issue 28): the flat form Stable-Baselines3
takes (item 12), Reach's spaces without a gripper (item 11), and an environment built
directly that keeps its time limit, has one arm and prints nothing per stop (item 15)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env

from armfleet.envs import REACH_ID, HandoverEnv, InvalidAction, InvalidOption, ReachEnv
from armfleet.envs.registration import REACH_MAX_STEPS


@pytest.fixture(scope="module")
def flat_reach() -> Iterator[ReachEnv]:
    env = ReachEnv(arm_count=2, flat=True)
    yield env
    env.close()


def test_reach_built_directly_has_one_arm_and_no_gripper_entry() -> None:
    env = ReachEnv()
    try:
        assert env.arm_names == ["arm0"]
        assert list(env.arm_action_space("arm0").spaces) == ["joint_deltas"]
        assert "gripper_width" not in env.arm_observation_space("arm0").spaces
        # The gripper entry stays where a task uses the fingers.
    finally:
        env.close()
    handover = HandoverEnv(control_period=50)
    try:
        assert "gripper" in handover.arm_action_space("bob").spaces
    finally:
        handover.close()


def test_reach_built_directly_is_truncated_at_its_time_limit() -> None:
    env = ReachEnv(control_period=1)  # 200 steps of 1 ms: quick
    try:
        for _ in range(2):  # the count starts again at reset
            env.reset(seed=2)
            hold = {"arm0": {"joint_deltas": np.zeros(7, np.float32)}}
            ends = []
            for step in range(1, REACH_MAX_STEPS + 1):
                _, _, terminated, truncated, _ = env.step(hold)
                if terminated or truncated:
                    ends.append((step, terminated, truncated))
            assert ends == [(REACH_MAX_STEPS, False, True)]
    finally:
        env.close()
    with pytest.raises(InvalidOption, match=r"max_episode_steps = 0 is invalid; valid: a whole"):
        ReachEnv(max_episode_steps=0)


def test_flat_spaces_are_one_normalised_box_each(flat_reach: ReachEnv) -> None:
    action_space, observation_space = flat_reach.action_space, flat_reach.observation_space
    assert isinstance(action_space, spaces.Box) and action_space.shape == (14,)
    assert np.all(action_space.low == -1) and np.all(action_space.high == 1)
    assert isinstance(observation_space, spaces.Box) and observation_space.dtype == np.float32
    observation, _ = flat_reach.reset(seed=4)
    assert observation in observation_space
    # The flat observation is Gymnasium's flatten of the Dict one.
    dict_space = gym.spaces.Dict(
        {name: flat_reach.arm_observation_space(name) for name in flat_reach.arm_names}
    )
    expected = gym.spaces.flatten(dict_space, flat_reach.dict_observation())
    np.testing.assert_array_equal(observation, expected)


def test_a_flat_action_maps_onto_each_entrys_range(flat_reach: ReachEnv) -> None:
    flat_reach.reset(seed=5)
    start = {name: flat_reach.commander(name).target for name in flat_reach.arm_names}
    # arm0: every joint +1 (the full +0.05 rad step); arm1: -1 on joint 0, 0 elsewhere.
    action = np.zeros(14, np.float32)
    action[:7] = 1.0
    action[7] = -1.0
    info = flat_reach.step(action)[4]
    assert info["clipped"] == [] and info["refused"] == {}
    box = flat_reach.arm_action_space("arm0")["joint_deltas"]
    assert isinstance(box, spaces.Box)
    bound = box.high.astype(float)
    np.testing.assert_allclose(flat_reach.commander("arm0").target - start["arm0"], bound)
    moved = flat_reach.commander("arm1").target - start["arm1"]
    np.testing.assert_allclose(moved, [-bound[0], 0, 0, 0, 0, 0, 0], atol=1e-12)
    # Out of [-1, 1]: clipped and named; not numbers or the wrong shape: refused.
    action[:] = 0.0
    action[3] = 7.0
    assert flat_reach.step(action)[4]["clipped"] == ["arm0.joint_deltas"]
    with pytest.raises(InvalidAction, match=r"got shape \(7,\); valid: 14 finite numbers"):
        flat_reach.step(np.zeros(7, np.float32))
    with pytest.raises(InvalidAction, match=r"element 2 is nan"):
        flat_reach.step(np.where(np.arange(14) == 9, np.nan, 0.0))


def test_the_registered_id_takes_flat_and_passes_both_checkers() -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check

    env = gym.make(REACH_ID, flat=True)
    try:
        check_env(env.unwrapped)
        sb3_check(env)  # warns and raises on what Stable-Baselines3 cannot take
    finally:
        env.close()


def test_a_stop_prints_nothing_and_is_kept_in_info() -> None:
    """In a fresh interpreter with no logging set up (Python then prints warnings), an
    arm driven into the floor stops; nothing reaches stderr, and ``info`` says why."""
    script = textwrap.dedent(
        """
        import numpy as np
        from armfleet.envs import ReachEnv

        env = ReachEnv()
        env.reset(seed=0)
        deltas = np.array([0, 0.05, 0, 0.05, 0, 0, 0], np.float32)
        for _ in range(200):
            _, _, terminated, _, info = env.step({"arm0": {"joint_deltas": deltas}})
            if terminated:
                break
        print(info["stopped"], info["stop_reasons"])
        env.close()
        """
    )
    run = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=300, check=True
    )
    assert run.stdout.startswith("['arm0'] {'arm0': 'touched ground"), run.stdout
    assert run.stderr == ""


def test_the_parallel_env_refuses_the_flat_form_in_one_line() -> None:
    from armfleet.envs import MultiArmParallelEnv, ReachTask

    with pytest.raises(InvalidOption, match=r"^flat = True is invalid; valid: a MultiArmEnv"):
        MultiArmParallelEnv(ReachTask(), flat=True)
