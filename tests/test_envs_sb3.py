"""Stable-Baselines3 trains on Reach out of the box (issue 28, item 12): ``flat=True`` and
nothing else, no wrapper of one's own. A few hundred steps each of PPO and SAC: the point
is that they run and update their networks on the environment's own spaces, not that
they learn (benchmarks/learning.py does that)."""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

from armfleet.envs import REACH_ID

torch = pytest.importorskip("torch")
sb3 = pytest.importorskip("stable_baselines3")


@pytest.fixture
def reach() -> Iterator[gym.Env[np.ndarray, np.ndarray]]:
    torch.set_num_threads(1)
    env = gym.make(REACH_ID, flat=True)
    yield env
    env.close()


def parameters(model: object) -> np.ndarray:
    policy = model.policy  # type: ignore[attr-defined]
    return np.concatenate([p.detach().numpy().ravel() for p in policy.parameters()])


def test_ppo_trains_on_flat_reach(reach: gym.Env[np.ndarray, np.ndarray]) -> None:
    model = sb3.PPO(
        "MlpPolicy", reach, n_steps=128, batch_size=64, n_epochs=2, seed=0,
        policy_kwargs={"net_arch": [32, 32]},
    )  # fmt: skip
    before = parameters(model)
    model.learn(total_timesteps=256)
    assert model.num_timesteps == 256
    assert not np.array_equal(parameters(model), before)  # two updates happened
    observation, _ = reach.reset(seed=1)
    action, _ = model.predict(observation, deterministic=True)
    assert action in reach.action_space


def test_sac_trains_on_flat_reach(reach: gym.Env[np.ndarray, np.ndarray]) -> None:
    model = sb3.SAC(
        "MlpPolicy", reach, learning_starts=100, batch_size=32, seed=0,
        policy_kwargs={"net_arch": [32, 32]},
    )  # fmt: skip
    before = parameters(model)
    model.learn(total_timesteps=300)
    assert model.num_timesteps == 300
    assert not np.array_equal(parameters(model), before)
    buffer = model.replay_buffer
    assert buffer is not None and buffer.pos == 300
    rewards = buffer.rewards[:300, 0]
    assert np.all(np.isfinite(rewards)) and np.all(rewards <= 1.0)  # Reach's reward bounds
    observation, _ = reach.reset(seed=1)
    action, _ = model.predict(observation, deterministic=True)
    assert action in reach.action_space
