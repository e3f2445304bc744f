"""Several arms of one world as one Gymnasium environment: ``Dict`` actions and
observations keyed by arm name.

A step checks every arm's action (:mod:`armfleet.envs.actions`; a bad one is refused
with nothing applied and no time passed), sends every arm its command
(:mod:`armfleet.envs.arm_commander`), runs ``control_period`` physics steps, and asks the
task for the reward. A reset launches the task's scene anew (``armfleet.launch`` with one
model library for all episodes, ~70 ms for two Pandas and a table set), so that
``reset(seed=s)`` starts every episode from the same state and draws the same things.
"""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from armfleet.description import ModelLibrary
from armfleet.envs.actions import ActionKind, StepLimits, arm_action_space, check_action
from armfleet.envs.arm_commander import ArmCommander
from armfleet.envs.errors import EnvNotReset, InvalidOption
from armfleet.envs.observations import ArmObserver
from armfleet.envs.rendering import DEFAULT_SIZE, RenderMode, check_size, render_rgb
from armfleet.envs.stop_policy import StopPolicy
from armfleet.envs.tasks.task import Evaluation, SceneTask, Task
from armfleet.messages import ArmMode
from armfleet.spec import FleetSpec
from armfleet.world import World
from armfleet.world.launch import launch

logger = logging.getLogger("armfleet")

#: Longest control period [physics steps].
MAX_CONTROL_PERIOD = 10_000
_STOPPED = (ArmMode.PROTECTIVE_STOP, ArmMode.ERROR)

Observation = dict[str, Any]
Action = dict[str, Any]


class MultiArmEnv(gym.Env[Observation, Action]):
    """The arms of a launch spec, driven together (see the module docstring and
    docs/envs.md).

    Args:
        task: what the arms are to do (:class:`~armfleet.envs.tasks.ReachTask`, ...),
            or a launch spec (a :class:`~armfleet.FleetSpec`, a path, or a shipped
            spec's name) for its scene with no reward (:class:`SceneTask`).
        action_kind: ``"joint_positions"``, ``"joint_deltas"`` or ``"tool_delta"``
            (:class:`~armfleet.envs.actions.ActionKind`).
        control_period: physics steps per environment step, in [1, 10000].
        on_stop: ``"terminate"`` or ``"reset"``: what a protective stop or an arm fault
            does (:class:`~armfleet.envs.stop_policy.StopPolicy`).
        render_mode: None, ``"rgb_array"`` (PyBullet's software renderer) or
            ``"human"`` (the world's MeshCat viewer, started for each episode).
        render_size: (width, height) of ``rgb_array`` images [pixels].
        max_joint_step_rad: bound of ``joint_deltas`` actions [rad].
        max_tool_step_m, max_tool_step_rad: bounds of ``tool_delta`` actions [m, rad].

    Raises:
        InvalidOption: an option out of its choices (the message lists them).
        SpecError, ArmfleetError: a spec that does not launch.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array", "human"], "render_fps": 50}  # noqa: RUF012

    def __init__(
        self,
        task: Task | FleetSpec | str | Path,
        *,
        action_kind: ActionKind | str = ActionKind.JOINT_DELTAS,
        control_period: int = 20,
        on_stop: StopPolicy | str = StopPolicy.TERMINATE,
        render_mode: str | None = None,
        render_size: tuple[int, int] = DEFAULT_SIZE,
        max_joint_step_rad: float = 0.05,
        max_tool_step_m: float = 0.02,
        max_tool_step_rad: float = 0.1,
    ) -> None:
        if isinstance(task, FleetSpec | str | Path):
            task = SceneTask(task)
        if not isinstance(task, Task):
            raise InvalidOption(
                "task", task, "an armfleet.envs Task, a FleetSpec, or a launch spec's path or name"
            )
        self._task = task
        self._kind = ActionKind.parse(action_kind)
        self._period = _control_period(control_period)
        self._stop_policy = StopPolicy.parse(on_stop)
        mode = RenderMode.parse(render_mode)
        self.render_mode = None if mode is None else mode.value
        self._render_size = check_size(render_size)
        self._limits = StepLimits(max_joint_step_rad, max_tool_step_m, max_tool_step_rad)
        spec = task.spec()
        self._spec = dataclasses.replace(
            spec, world=dataclasses.replace(spec.world, viewer=mode is RenderMode.HUMAN)
        )
        self._models = ModelLibrary()  # every episode's arms from one library
        self._viewer_port: int | None = None
        self._world = self._launch()
        try:
            self._build_spaces(task)
        except BaseException:
            self._world.close()
            raise
        self.action_space = self._actions
        self.observation_space = self._observations
        rate = {"render_fps": 1.0 / (self._world.dt * self._period)}  # this env's own
        self.metadata = {**self.metadata, **rate}
        self._fresh = True  # the world is as launched: the first reset takes it
        self._commanders: dict[str, ArmCommander] = {}

    # -- what it is ----------------------------------------------------------------------
    @property
    def task(self) -> Task:
        return self._task

    @property
    def world(self) -> World:
        """The current episode's world (for inspection; a new one after every reset)."""
        return self._world

    @property
    def arm_names(self) -> list[str]:
        return list(self._observers)

    @property
    def action_kind(self) -> ActionKind:
        return self._kind

    @property
    def control_period(self) -> int:
        """Physics steps per environment step."""
        return self._period

    @property
    def step_s(self) -> float:
        """Simulated time of one environment step [s]."""
        return self._world.dt * self._period

    def arm_action_space(self, arm: str) -> spaces.Dict:
        """The action space of ``arm`` (the entry of :attr:`action_space`)."""
        return _entry(self._actions, arm)

    def arm_observation_space(self, arm: str) -> spaces.Dict:
        """The observation space of ``arm`` (the entry of :attr:`observation_space`)."""
        return _entry(self._observations, arm)

    def commander(self, arm: str) -> ArmCommander:
        """The command state of ``arm`` this episode (its targets)."""
        if arm not in self._commanders:
            raise EnvNotReset(f"commander({arm!r})")
        return self._commanders[arm]

    # -- the Gymnasium API ---------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Start an episode from the task's scene, launched anew; the task draws its
        targets with the environment's generator (seeded by ``seed``). ``options`` are
        not used."""
        super().reset(seed=seed, options=options)
        if not self._fresh:
            self._world.close()
            self._world = self._launch()
        self._fresh = False
        self._task.reset(self._world, self.np_random)
        self._commanders = {
            name: ArmCommander(self._world, self._world.arm(name), self._kind)
            for name in self._observers
        }
        evaluation = self._task.evaluate(self._world)
        return self._observe(), self._info(evaluation, [], {}, [])

    def step(self, action: Action) -> tuple[Observation, SupportsFloat, bool, bool, dict[str, Any]]:
        """Apply every arm's action, run ``control_period`` physics steps, evaluate.

        Raises:
            InvalidAction: a missing or unknown arm or entry, a wrong shape, a value
                that is not finite; nothing was applied and no time passed.
            EnvNotReset: before the first reset.
        """
        if not self._commanders:
            raise EnvNotReset("step")
        checked, clipped = check_action(self._actions, action)
        refused = {}
        for name, commander in self._commanders.items():
            reason = commander.apply(checked[name])
            if reason:
                refused[name] = reason
        world = self._world
        for _ in range(self._period):
            world.step()
        evaluation = self._task.evaluate(world)
        stopped = [name for name, arm in world.arms.items() if arm.mode in _STOPPED]
        terminated = (evaluation.success and self._task.terminate_on_success) or bool(
            stopped and self._stop_policy is StopPolicy.TERMINATE
        )
        if stopped and self._stop_policy is StopPolicy.RESET:
            for name in stopped:
                world.arm(name).reset()
                self._commanders[name].rebase()
        info = self._info(evaluation, stopped, refused, clipped)
        return self._observe(), float(evaluation.reward), terminated, False, info

    def render(self) -> npt.NDArray[np.uint8] | None:
        """An RGB image (``rgb_array``); None for ``human`` (the viewer follows the
        world by itself) and without a render mode."""
        if self.render_mode == RenderMode.RGB_ARRAY.value:
            return render_rgb(self._world, self._render_size)
        return None

    def close(self) -> None:
        """Close the world (its PyBullet client, its viewer); closing again does nothing."""
        world = getattr(self, "_world", None)
        if world is not None:
            world.close()
        self._commanders = {}

    # -- the rest ------------------------------------------------------------------------
    def _build_spaces(self, task: Task) -> None:
        arms = list(self._world.arms.values())
        if not arms:
            raise InvalidOption("task", task.name, "a scene with at least one arm")
        objects = list(self._world.objects)
        self._observers = {
            arm.name: ArmObserver(arm, objects, task.arm_spaces(arm.name)) for arm in arms
        }
        self._actions = spaces.Dict(
            {arm.name: arm_action_space(arm, self._kind, self._limits) for arm in arms}
        )
        self._observations = spaces.Dict(
            {name: observer.space for name, observer in self._observers.items()}
        )

    def _launch(self) -> World:
        # Every episode's viewer on the first one's port: the page stays where it is.
        world = launch(self._spec, models=self._models, viewer_port=self._viewer_port)
        if self._spec.world.viewer:
            if world.viewer is None:
                logger.warning("render_mode='human': no viewer (%s)", world.viewer_error)
            else:
                if self._viewer_port is None:
                    logger.info("viewer at %s", world.viewer.url)
                self._viewer_port = world.viewer.port
        return world

    def _observe(self) -> Observation:
        return {
            name: observer.observe(self._world, self._task.observe(self._world, name))
            for name, observer in self._observers.items()
        }

    def _info(
        self,
        evaluation: Evaluation,
        stopped: list[str],
        refused: dict[str, str],
        clipped: list[str],
    ) -> dict[str, Any]:
        return {
            "success": evaluation.success,
            "stopped": stopped,
            "refused": refused,
            "clipped": clipped,
            "time_s": self._world.time,
            **evaluation.info,
        }

    def __str__(self) -> str:
        return repr(self)

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}({self._task.name}, arms={self.arm_names}, "
            f"action_kind={self._kind.value!r}, control_period={self._period})"
        )


def _entry(space: spaces.Dict, arm: str) -> spaces.Dict:
    if arm not in space.spaces:
        raise InvalidOption("arm", arm, list(space.spaces))
    entry = space.spaces[arm]
    assert isinstance(entry, spaces.Dict)
    return entry


def _control_period(value: object) -> int:
    valid = f"a whole number of physics steps in [1, {MAX_CONTROL_PERIOD}]"
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InvalidOption("control_period", value, valid)
    if not 1 <= value <= MAX_CONTROL_PERIOD:
        raise InvalidOption("control_period", value, valid)
    return int(value)
