"""What a stop costs: a penalty that makes ending an episode by a crash never pay.

With a reward that is negative at every step, an episode ended early by a protective stop
(``terminated=True``) collects fewer negative rewards than one that goes on: a learner
finds that crashing pays (an outside Stable-Baselines3 run: episodes ended by a collision
scored -75.7 on average, full ones -156.9, and the trained policy crashed in 52 of 100
episodes). So a step in which an arm stops also costs ``P``, made from the task's bounds
on one step's reward, ``low <= r <= high`` (:meth:`Task.reward_bounds`), and the episode
length ``T``::

    P = T * (max(high, 0) - min(low, 0)) + 1

An episode ended by a stop at step ``k <= T`` then returns at most ``k * high - P``, and
any episode that runs to the time limit at least ``T * low``; ``k * high - P < T * low``
for every ``k``. The bound holds whatever the policy did before the stop, so no crash,
early or late, beats going on (``tests/test_envs_rewards.py`` checks it with the real
reward and a provoked stop). Reach with one arm: ``low = -2`` (the distance term's cap),
``high = 1`` (the success bonus), ``T = 200``: ``P = 601``.
"""

from __future__ import annotations

import math

from armfleet.checks.real_numbers import is_real
from armfleet.envs.errors import InvalidOption
from armfleet.envs.tasks.task import Task


def default_stop_penalty(bounds: tuple[float, float], max_episode_steps: int) -> float:
    """``P`` of the module docstring for one step's reward ``bounds`` = (low, high)."""
    low, high = bounds
    return max_episode_steps * (max(high, 0.0) - min(low, 0.0)) + 1.0


def stop_penalty_for(task: Task, max_episode_steps: int, given: object) -> float:
    """The penalty an environment uses: ``given``, else made from the task's reward bounds
    (0 for a task that declares none).

    Raises:
        InvalidOption: ``given`` is not a finite number >= 0, or the task's bounds are not
            finite numbers with low <= high.
    """
    if given is not None:
        value = float(given) if is_real(given) else math.nan  # type: ignore[arg-type]
        if not math.isfinite(value) or value < 0:
            raise InvalidOption("stop_penalty", given, "None, or a finite number >= 0")
        return value
    bounds = task.reward_bounds()
    if bounds is None:
        return 0.0
    low, high = bounds
    finite = is_real(low) and is_real(high) and math.isfinite(low) and math.isfinite(high)
    if not finite or low > high:
        raise InvalidOption(
            "reward_bounds", bounds, f"{task.name}: finite numbers (low, high), low <= high"
        )
    return default_stop_penalty((low, high), max_episode_steps)
