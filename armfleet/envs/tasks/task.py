"""What a task adds to a world: its scene, what it draws at reset, what each arm observes
of it, and its reward."""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from gymnasium import spaces

from armfleet.messages import FloatArray
from armfleet.spec import FleetSpec, load_spec
from armfleet.world import World


@dataclass(frozen=True)
class Evaluation:
    """How the episode stands after a step.

    Attributes:
        reward: the step's reward.
        success: whether the task is done (the episode terminates when the task says so).
        info: the task's figures for ``info`` (distances, ...).
    """

    reward: float
    success: bool
    info: dict[str, object] = field(default_factory=dict)


class Task(ABC):
    """A task for :class:`~armfleet.envs.MultiArmEnv`.

    Attributes:
        terminate_on_success: end the episode (``terminated``) once :meth:`evaluate`
            reports success.
        uses_gripper: whether the arms' actions have a ``gripper`` entry (and their
            observations a ``gripper_width``), for arms with fingers.
    """

    terminate_on_success: bool = True
    uses_gripper: bool = True

    @property
    @abstractmethod
    def name(self) -> str:
        """A short name (for ``repr`` and the docs)."""

    @abstractmethod
    def spec(self) -> FleetSpec:
        """The scene every episode starts from (the environment turns its viewer off
        unless ``render_mode="human"``)."""

    def reset(self, world: World, rng: np.random.Generator) -> None:
        """Draw what the episode needs with ``rng`` (targets, object poses); the world is
        freshly launched and not stepped. Nothing by default."""
        del world, rng

    def arm_spaces(self, arm: str) -> dict[str, spaces.Box]:
        """The task's own observation entries for ``arm``; none by default."""
        del arm
        return {}

    def observe(self, world: World, arm: str) -> dict[str, FloatArray]:
        """The values of :meth:`arm_spaces` for ``arm`` now."""
        del world, arm
        return {}

    @abstractmethod
    def evaluate(self, world: World) -> Evaluation:
        """The reward and success after a step (and after reset, for ``info``)."""

    def reward_bounds(self) -> tuple[float, float] | None:
        """The lowest and highest reward :meth:`evaluate` gives in one step, or None if
        unknown. The environment's stop penalty is made from them (a stop then costs
        more than any episode that goes on: docs/envs.md); None by default (no penalty
        unless the environment is given one)."""
        return None


class SceneTask(Task):
    """Any launch spec, no goal: reward 0, never a success (an environment to drive,
    record or wrap with a reward of one's own).

    Args:
        spec: a spec, or a spec file (path or name of a shipped spec).
    """

    terminate_on_success = False

    def __init__(self, spec: FleetSpec | str | Path) -> None:
        self._spec = spec if isinstance(spec, FleetSpec) else load_spec(spec)
        self._spec = dataclasses.replace(
            self._spec, world=dataclasses.replace(self._spec.world, viewer=False)
        )

    @property
    def name(self) -> str:
        return f"scene {self._spec.source}"

    def spec(self) -> FleetSpec:
        return self._spec

    def evaluate(self, world: World) -> Evaluation:
        del world
        return Evaluation(0.0, False)

    def reward_bounds(self) -> tuple[float, float]:
        return (0.0, 0.0)
