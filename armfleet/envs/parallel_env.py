"""The same world as a PettingZoo ``ParallelEnv``: one agent per arm.

Each agent's action and observation are its arm's entries of
:class:`~armfleet.envs.MultiArmEnv`'s ``Dict`` spaces (the very same space objects). The
task's reward is shared: every agent gets it (a cooperative team). All agents end
together: on success, on a protective stop (with ``on_stop="terminate"``), or truncated
after ``max_cycles`` steps; ``agents`` is then empty until the next reset. ``state()``
is every arm's observation in one vector.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt
from gymnasium import spaces
from pettingzoo import ParallelEnv

from armfleet.envs.errors import EnvNotReset, InvalidOption
from armfleet.envs.multi_arm_env import MultiArmEnv
from armfleet.envs.tasks.task import Task
from armfleet.spec import FleetSpec

AgentObservation = dict[str, Any]
AgentAction = dict[str, Any]


class MultiArmParallelEnv(ParallelEnv[str, AgentObservation, AgentAction]):  # type: ignore[misc]
    """One agent per arm of ``task``'s world (see the module docstring).

    Args:
        task: as :class:`~armfleet.envs.MultiArmEnv` takes it.
        max_cycles: steps after which the episode is truncated, >= 1.
        **options: the options of :class:`~armfleet.envs.MultiArmEnv`
            (``action_kind``, ``control_period``, ``on_stop``, ``render_mode``, ...).
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array", "human"],
        "name": "armfleet_multi_arm_v0",
        "is_parallelizable": True,
    }

    def __init__(
        self, task: Task | FleetSpec | str | Path, *, max_cycles: int = 1000, **options: Any
    ) -> None:
        if isinstance(max_cycles, bool) or not isinstance(max_cycles, int) or max_cycles < 1:
            raise InvalidOption("max_cycles", max_cycles, "a whole number >= 1")
        for option in ("flat", "max_episode_steps"):
            if option in options:
                valid = "a MultiArmEnv option; agents have Dict spaces, max_cycles ends episodes"
                raise InvalidOption(option, options[option], valid)
        self._env = MultiArmEnv(task, max_episode_steps=max_cycles, **options)
        #: Every arm's observation in one float32 vector (``state()``), e.g. for a
        #: centralised critic: Gymnasium's ``flatten_space`` of the whole ``Dict``.
        self.state_space = spaces.flatten_space(self._env.observation_space)
        self._observation: dict[str, AgentObservation] | None = None
        self.render_mode = self._env.render_mode
        self.possible_agents = self._env.arm_names
        self.agents: list[str] = []
        #: Steps of an episode before truncation.
        self.max_cycles = max_cycles
        self._cycles = 0

    @property
    def env(self) -> MultiArmEnv:
        """The Gymnasium environment underneath (its world, task and commanders)."""
        return self._env

    def observation_space(self, agent: str) -> spaces.Dict:
        """The arm's observation space: the same object on every call."""
        return self._env.arm_observation_space(agent)

    def action_space(self, agent: str) -> spaces.Dict:
        """The arm's action space: the same object on every call."""
        return self._env.arm_action_space(agent)

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, AgentObservation], dict[str, dict[str, Any]]]:
        observation, info = self._env.reset(seed=seed, options=options)
        self._observation = observation
        self.agents = list(self.possible_agents)
        self._cycles = 0
        return observation, {agent: dict(info) for agent in self.agents}

    def step(self, actions: dict[str, AgentAction]) -> tuple[
        dict[str, AgentObservation],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:  # fmt: skip
        """Step every arm; ``actions`` holds one entry per agent (all are alive together).

        Raises:
            InvalidAction: as :meth:`MultiArmEnv.step`; nothing applied, no time passed.
            EnvNotReset: before reset, or once the episode has ended.
        """
        if not self.agents:
            raise EnvNotReset("step (the episode has ended, or not begun)")
        observation, reward, terminated, _, info = self._env.step(actions)
        self._observation = observation
        self._cycles += 1
        truncated = not terminated and self._cycles >= self.max_cycles
        acting = self.agents
        if terminated or truncated:
            self.agents = []
        return (
            observation,
            {agent: float(reward) for agent in acting},
            {agent: terminated for agent in acting},
            {agent: truncated for agent in acting},
            {agent: dict(info) for agent in acting},
        )

    def state(self) -> npt.NDArray[np.float32]:
        """The latest observation of every arm, flattened into :attr:`state_space`.

        Raises:
            EnvNotReset: before the first reset.
        """
        if self._observation is None:
            raise EnvNotReset("state")
        flat = np.asarray(spaces.flatten(self._env.observation_space, self._observation))
        return flat.astype(np.float32)

    def render(self) -> npt.NDArray[np.uint8] | None:
        return self._env.render()

    def close(self) -> None:
        self._env.close()
