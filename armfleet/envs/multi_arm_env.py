"""Several arms of one world as one Gymnasium environment: ``Dict`` actions and
observations keyed by arm name.

A step checks every arm's action (:mod:`armfleet.envs.actions`; a bad one is refused
with nothing applied and no time passed), sends every arm its command
(:mod:`armfleet.envs.arm_commander`), runs ``control_period`` physics steps, and asks the
task for the reward. A reset restores the world as it was launched, from a snapshot taken
once (:mod:`armfleet.world.world_snapshot`: about 1 ms, against 65-130 ms to launch the
scene anew), so that ``reset(seed=s)`` starts every episode from the same state, bit for
bit, and draws the same things. The scene is launched anew only when the snapshot cannot
serve: the world was changed (an arm or object added or removed, a front end attached), or
``render_mode="human"`` (every episode on a new world, shown by its viewer).
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
from armfleet.envs.flat_spaces import FlatSpaces
from armfleet.envs.observations import ArmObserver
from armfleet.envs.rendering import DEFAULT_SIZE, RenderMode, check_size, render_rgb
from armfleet.envs.servo_controller import servo_spec
from armfleet.envs.stop_messages import StopMessages
from armfleet.envs.stop_penalty import stop_penalty_for
from armfleet.envs.stop_policy import StopPolicy
from armfleet.envs.tasks.task import Evaluation, SceneTask, Task
from armfleet.messages import ArmMode
from armfleet.spec import FleetSpec
from armfleet.world import World
from armfleet.world.launch import launch
from armfleet.world.object_state import UnsavedState
from armfleet.world.world_snapshot import SnapshotStale, WorldSnapshot

logger = logging.getLogger("armfleet")

#: Longest control period [physics steps].
MAX_CONTROL_PERIOD = 10_000
#: Episode length of an environment not told one [environment steps]; the longest taken.
DEFAULT_MAX_EPISODE_STEPS, MAX_EPISODE_STEPS = 1000, 1_000_000
_STOPPED = (ArmMode.PROTECTIVE_STOP, ArmMode.ERROR)

Observation = dict[str, Any]
#: A ``Dict`` action, or with ``flat=True`` an array.
Action = dict[str, Any] | npt.NDArray[Any]


class MultiArmEnv(gym.Env[Observation, Action]):
    """The arms of a launch spec, driven together (see the module docstring and
    docs/envs.md).

    Args:
        task: what the arms are to do (:class:`~armfleet.envs.tasks.ReachTask`, ...),
            or a launch spec (a :class:`~armfleet.FleetSpec`, a path, or a shipped
            spec's name) for its scene with no reward (:class:`SceneTask`).
        action_kind: ``"joint_positions"``, ``"joint_deltas"``, ``"tool_delta"`` or
            ``"tool_servo"`` (:class:`~armfleet.envs.actions.ActionKind`; ``tool_servo``
            gives the arms a responsive controller: :mod:`armfleet.envs.servo_controller`).
        control_period: physics steps per environment step, in [1, 10000].
        on_stop: ``"terminate"`` or ``"reset"``: what a protective stop or an arm fault
            does (:class:`~armfleet.envs.stop_policy.StopPolicy`).
        render_mode: None, ``"rgb_array"`` (PyBullet's software renderer) or
            ``"human"`` (the world's MeshCat viewer, started for each episode).
        render_size: (width, height) of ``rgb_array`` images [pixels].
        max_joint_step_rad: bound of ``joint_deltas`` actions [rad].
        max_tool_step_m, max_tool_step_rad: bounds of ``tool_delta`` actions [m, rad].
        max_episode_steps: the episode is truncated (``truncated=True``) after this many
            steps, in [1, 1000000].
        stop_penalty: subtracted from the reward of a step in which an arm stops; by
            default made from the task's reward bounds so that a stop costs more than
            any episode that goes on (:mod:`armfleet.envs.stop_penalty`).
        flat: actions and observations as flat float32 ``Box``es, actions in [-1, 1]
            (:mod:`armfleet.envs.flat_spaces`: what Stable-Baselines3 takes).

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
        max_episode_steps: int = DEFAULT_MAX_EPISODE_STEPS,
        stop_penalty: float | None = None,
        flat: bool = False,
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
        self._max_steps = _max_episode_steps(max_episode_steps)
        self._stop_penalty = stop_penalty_for(task, self._max_steps, stop_penalty)
        if not isinstance(flat, bool):
            raise InvalidOption("flat", flat, "True or False")
        self._elapsed_steps = 0
        spec = task.spec()
        if self._kind is ActionKind.TOOL_SERVO:  # arms that follow a command at once
            spec = servo_spec(spec)
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
        self._flat = FlatSpaces(self._actions, self._observations) if flat else None
        self._stop_messages = StopMessages(self._observers)
        if self._flat is None:
            self.action_space: spaces.Space[Any] = self._actions
            self.observation_space: spaces.Space[Any] = self._observations
        else:
            self.action_space = self._flat.action_space
            self.observation_space = self._flat.observation_space
        rate = {"render_fps": 1.0 / (self._world.dt * self._period)}  # this env's own
        self.metadata = {**self.metadata, **rate}
        self._fresh = True  # the world is as launched: the first reset takes it
        #: The world as launched, restored by every reset (None: each reset launches anew).
        self._start: WorldSnapshot | None = self._save_start()
        self._commanders: dict[str, ArmCommander] = {}

    # -- what it is ----------------------------------------------------------------------
    @property
    def task(self) -> Task:
        return self._task

    @property
    def world(self) -> World:
        """The current episode's world (for inspection): the same one from episode to
        episode, restored by every reset, unless a reset had to launch it anew (the
        module docstring says when)."""
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

    @property
    def max_episode_steps(self) -> int:
        """Steps after which an episode is truncated."""
        return self._max_steps

    @property
    def stop_penalty(self) -> float:
        """Subtracted from the reward of a step in which an arm stops."""
        return self._stop_penalty

    @property
    def flat_spaces(self) -> FlatSpaces | None:
        """The flat form of the spaces (``flat=True``), else None."""
        return self._flat

    def commander(self, arm: str) -> ArmCommander:
        """The command state of ``arm`` this episode (its targets)."""
        if arm not in self._commanders:
            raise EnvNotReset(f"commander({arm!r})")
        return self._commanders[arm]

    # -- the Gymnasium API ---------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Start an episode from the task's scene as launched (restored from its snapshot,
        or launched anew: see the module docstring); the task draws its targets with the
        environment's generator (seeded by ``seed``). ``options`` are not used."""
        super().reset(seed=seed, options=options)
        self._elapsed_steps = 0
        self._restart_world()
        self._task.reset(self._world, self.np_random)
        self._commanders = {
            name: ArmCommander(self._world, self._world.arm(name), self._kind)
            for name in self._observers
        }
        evaluation = self._task.evaluate(self._world)
        return self._observe(), self._info(evaluation, [], {}, [])

    def step(self, action: Action) -> tuple[Observation, SupportsFloat, bool, bool, dict[str, Any]]:
        """Apply every arm's action, run ``control_period`` physics steps, evaluate.

        The reward is the task's, minus :attr:`stop_penalty` if an arm stopped;
        ``truncated`` once :attr:`max_episode_steps` steps are done.

        Raises:
            InvalidAction: a missing or unknown arm or entry, a wrong shape, a value
                that is not finite; nothing was applied and no time passed.
            EnvNotReset: before the first reset.
        """
        if not self._commanders:
            raise EnvNotReset("step")
        if self._flat is not None:
            action = self._flat.action(action)
        checked, clipped = check_action(self._actions, action)
        refused = {}
        world = self._world
        with self._stop_messages.taking() as stop_reasons:
            for name, commander in self._commanders.items():
                reason = commander.apply(checked[name])
                if reason:
                    refused[name] = reason
            for _ in range(self._period):
                world.step()
        self._elapsed_steps += 1
        evaluation = self._task.evaluate(world)
        stopped = [name for name, arm in world.arms.items() if arm.mode in _STOPPED]
        terminated = (evaluation.success and self._task.terminate_on_success) or bool(
            stopped and self._stop_policy is StopPolicy.TERMINATE
        )
        truncated = not terminated and self._elapsed_steps >= self._max_steps
        reward = float(evaluation.reward) - (self._stop_penalty if stopped else 0.0)
        if stopped and self._stop_policy is StopPolicy.RESET:
            for name in stopped:
                world.arm(name).reset()
                self._commanders[name].rebase()
        info = self._info(evaluation, stopped, refused, clipped)
        info["stop_reasons"] = dict(stop_reasons)
        return self._observe(), reward, terminated, truncated, info

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
        gripper = task.uses_gripper
        self._observers = {
            arm.name: ArmObserver(arm, objects, task.arm_spaces(arm.name), gripper=gripper)
            for arm in arms
        }
        self._actions = spaces.Dict(
            {
                arm.name: arm_action_space(arm, self._kind, self._limits, gripper=gripper)
                for arm in arms
            }
        )
        self._observations = spaces.Dict(
            {name: observer.space for name, observer in self._observers.items()}
        )

    def _restart_world(self) -> None:
        """The world as launched: the snapshot restored, else a world launched anew (and
        its snapshot restored at once, so that its solvers start as every restore's)."""
        fresh, self._fresh = self._fresh, False
        if self._start is not None:
            try:
                self._start.restore()
                return
            except SnapshotStale as exc:
                logger.debug("launching the scene anew: %s", exc)
        if fresh and self._start is None:
            return  # no snapshot: the world just launched is the first episode's
        self._world.close()
        self._world = self._launch()
        self._start = self._save_start()
        if self._start is not None:
            self._start.restore()

    def _save_start(self) -> WorldSnapshot | None:
        """A snapshot of the world just launched; None with a viewer (each episode a new
        world on screen), or if some state is out of the snapshot's reach."""
        if self._spec.world.viewer:
            return None
        try:
            return self._world.snapshot()
        except UnsavedState as exc:
            logger.warning("every reset launches the scene anew: %s", exc)
            return None

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
        """The observation: a ``Dict``'s value, or its flat form (``flat=True``)."""
        observation = self.dict_observation()
        if self._flat is None:
            return observation
        flat: Observation = self._flat.observation(observation)  # type: ignore[assignment]
        return flat

    def dict_observation(self) -> dict[str, Any]:
        """The observation as a ``Dict`` value (as without ``flat``), now."""
        return {
            name: observer.observe(
                self._world, self.commander(name).target, self._task.observe(self._world, name)
            )
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
            "stop_reasons": {},
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


def _max_episode_steps(value: object) -> int:
    valid = f"a whole number of steps in [1, {MAX_EPISODE_STEPS}]"
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InvalidOption("max_episode_steps", value, valid)
    if not 1 <= value <= MAX_EPISODE_STEPS:
        raise InvalidOption("max_episode_steps", value, valid)
    return int(value)
