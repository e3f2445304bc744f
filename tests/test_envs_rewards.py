"""A stop never pays (issue 28, item 10): the reward's terms, their bounds, and the stop
penalty, checked against the bound's algebra and in a Reach episode ended by a real stop
(an arm driven into the floor)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from armfleet.envs import HandoverTask, ReachEnv, ReachTask, SceneTask, Task
from armfleet.envs.registration import HANDOVER_MAX_STEPS, REACH_MAX_STEPS, SCENE_MAX_STEPS
from armfleet.envs.stop_penalty import default_stop_penalty
from armfleet.envs.tasks.reach_task import DISTANCE_CAP_M

#: Joint deltas that fold the Panda's shoulder and elbow forward: the hand reaches the
#: floor within ~2 s [rad per step].
INTO_THE_FLOOR = np.array([0.0, 0.05, 0.0, 0.05, 0.0, 0.0, 0.0], np.float32)


@pytest.mark.parametrize(
    ("task", "steps"),
    [
        (ReachTask(1), REACH_MAX_STEPS),
        (ReachTask(8, success_bonus=100.0), REACH_MAX_STEPS),
        (HandoverTask("dense"), HANDOVER_MAX_STEPS),
        (HandoverTask("sparse"), HANDOVER_MAX_STEPS),
        (SceneTask("bob_and_toby"), SCENE_MAX_STEPS),
    ],
    ids=["reach-1", "reach-8-bonus-100", "handover-dense", "handover-sparse", "scene"],
)
def test_a_stop_at_any_step_returns_less_than_any_full_episode(task: Task, steps: int) -> None:
    """With every step's reward in [low, high]: a stop at step k returns at most
    k * high - P (the stop's step included), a full episode at least steps * low."""
    bounds = task.reward_bounds()
    assert bounds is not None
    low, high = bounds
    penalty = default_stop_penalty(bounds, steps)
    for k in range(1, steps + 1):
        best_stopped = k * high - penalty
        worst_full = steps * low
        assert best_stopped < worst_full, (k, best_stopped, worst_full)


@pytest.fixture
def reach() -> Iterator[ReachEnv]:
    env = ReachEnv()  # one Panda, 200 steps, joint deltas
    yield env
    env.close()


def reach_reward(env: ReachEnv, info: dict[str, object]) -> float:
    """The task's reward from the step's distances (the docs' formula, without a stop)."""
    task = env.task
    assert isinstance(task, ReachTask)
    distances = info["distance_m"]
    assert isinstance(distances, dict)
    bonus = task.success_bonus if info["success"] else 0.0
    return float(-sum(min(d, DISTANCE_CAP_M) for d in distances.values()) + bonus)


def test_an_episode_ended_by_a_stop_returns_less_than_going_on(reach: ReachEnv) -> None:
    task = reach.task
    bounds = task.reward_bounds()
    assert bounds is not None
    low, high = bounds
    assert reach.stop_penalty == default_stop_penalty(bounds, REACH_MAX_STEPS)
    # The arm driven into the floor: the step it touches stops it and ends the episode.
    reach.reset(seed=0)
    crashed, rewards = None, []
    down = {"arm0": {"joint_deltas": INTO_THE_FLOOR}}
    for step in range(1, REACH_MAX_STEPS + 1):
        _, reward, terminated, truncated, info = reach.step(down)
        rewards.append(float(reward))
        assert not truncated
        if terminated:
            crashed = step
            break
        assert low <= float(reward) <= high and float(reward) == reach_reward(reach, info)
    assert crashed is not None and info["stopped"] == ["arm0"] and not info["success"]
    assert "ground" in info["stop_reasons"]["arm0"]
    # The stop's step: the task's reward there, less the penalty.
    assert rewards[-1] == pytest.approx(reach_reward(reach, info) - reach.stop_penalty, abs=1e-9)
    stopped_return = sum(rewards)
    # Below every episode that runs to the time limit (the bound) ...
    assert stopped_return < REACH_MAX_STEPS * low
    # ... and below the same episode's start held to the time limit (measured).
    reach.reset(seed=0)
    held_return, length = 0.0, 0
    zero = {"arm0": {"joint_deltas": np.zeros(7, np.float32)}}
    while True:
        _, reward, terminated, truncated, info = reach.step(zero)
        held_return += float(reward)
        length += 1
        if terminated or truncated:
            break
    assert (length, truncated, info["stopped"]) == (REACH_MAX_STEPS, True, [])
    assert stopped_return < held_return


def test_the_stop_penalty_can_be_given_and_is_refused_when_negative() -> None:
    from armfleet.envs import InvalidOption

    with pytest.raises(InvalidOption, match=r"stop_penalty = -1 is invalid; valid: None"):
        ReachEnv(stop_penalty=-1)
    env = ReachEnv(stop_penalty=5.0, max_episode_steps=50)
    assert (env.stop_penalty, env.max_episode_steps) == (5.0, 50)
    env.close()
