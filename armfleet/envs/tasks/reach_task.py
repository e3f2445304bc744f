"""Reach: a row of Pandas, each sent to a random reachable tool0 pose.

The scene is the Reach sweep's (:mod:`armfleet.scenarios.reach`): ``arm_count``
Pandas ``arm0``, ``arm1``, ... along x, ``spacing_m`` apart, facing +y. At reset each arm
gets one target drawn with the episode's generator, in its ``target_region``
(:class:`TargetRegion`): ``"workspace"`` (default), the tool0 pose of a random joint
configuration clear of the limits, the floor and the arm itself
(:func:`~armfleet.scenarios.reach_targets.draw_row_targets`; 0.22-1.08 m from tool0's
start); ``"near"``, a position drawn uniformly in a cube of side :data:`NEAR_CUBE_M`
(0.3 m) centred on tool0's start, at least ``min_tool_height_m`` high, with tool0's start
orientation (as panda-gym's PandaReach: its goals lie in a 0.3 m cube in front of the
gripper).
Each arm observes its ``target_pose`` and ``target_offset``: the target's position less
tool0's, along the world axes [m] (what the reward measures, and what a policy moves
along).
Reward, every step: minus the sum over arms of tool0's distance to its target's position
[m], each capped at :data:`DISTANCE_CAP_M` (so that a step's reward is bounded), plus
``success_bonus`` in the step that succeeds: once every tool0 is within ``tolerance_m``
of its target's position. The arms have no gripper action (nor observed width): reaching
needs none, and random finger commands only add noise to learn through.
``model`` makes the row of another arm: a shipped model, one's own by name, or a model
file (docs/own-robot.md), all its joints driven as a Panda's.
"""

from __future__ import annotations

import enum
import os
import weakref
from pathlib import Path

import numpy as np
from gymnasium import spaces

from armfleet.checks.model_reference import is_model_file
from armfleet.checks.real_numbers import real_number
from armfleet.envs.choices import choose
from armfleet.envs.errors import InvalidOption
from armfleet.envs.observations import WORKSPACE_M, pose_space
from armfleet.envs.poses import pose_vector
from armfleet.envs.tasks.task import Evaluation, Task
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.messages import FloatArray
from armfleet.scenarios.reach import FACING_DEG, MODEL
from armfleet.scenarios.reach_targets import ClearanceProbe, draw_row_targets
from armfleet.spec import FleetSpec
from armfleet.spec.fleet_spec import ArmSpec, WorldSpec
from armfleet.world import World

#: Arms a Reach environment takes.
MAX_ARMS = 8
#: Each arm's distance term of the reward is capped here [m] (a Panda's tool0 and target
#: are never this far apart: both lie within its ~0.9 m reach of the shoulder).
DISTANCE_CAP_M = 2.0
#: Added to the reward in the step that succeeds.
SUCCESS_BONUS = 1.0
#: Side of the cube ``"near"`` targets are drawn in, centred on tool0's start [m].
NEAR_CUBE_M = 0.3


class TargetRegion(enum.Enum):
    """Where Reach draws its targets (see the module docstring)."""

    WORKSPACE = "workspace"
    NEAR = "near"

    @classmethod
    def parse(cls, value: object) -> TargetRegion:
        """``value`` as a region (the enum or its name); InvalidOption lists them."""
        return choose(cls, value, "target_region")


class ReachTask(Task):
    """N arms (Pandas by default) reach random targets (see the module docstring).

    Args:
        arm_count: arms in the row, 1 to :data:`MAX_ARMS`.
        spacing_m: distance between neighbouring bases [m], in [0.5, 5].
        tolerance_m: a target is reached within this distance [m], in (0, 0.5].
        limit_margin: fraction of each joint's range the drawn configurations keep clear.
        min_tool_height_m: lowest tool0 height of a target [m].
        model: the arms' model (``panda`` by default): a shipped model, one's own by name,
            or a model file's path (made absolute here: episodes and vector workers read
            the same file) or ``package://`` URI. An unknown model or a bad file is refused
            when the environment is made.
        success_bonus: added to the reward in the step that succeeds, in [0, 100].
        target_region: ``"workspace"`` or ``"near"`` (:class:`TargetRegion`).
    """

    uses_gripper = False

    def __init__(
        self,
        arm_count: int = 1,
        spacing_m: float = 1.0,
        tolerance_m: float = 0.02,
        limit_margin: float = 0.1,
        min_tool_height_m: float = 0.1,
        model: str | os.PathLike[str] = MODEL,
        success_bonus: float = SUCCESS_BONUS,
        target_region: TargetRegion | str = TargetRegion.WORKSPACE,
    ) -> None:
        if isinstance(arm_count, bool) or not isinstance(arm_count, int | np.integer):
            raise InvalidOption("arm_count", arm_count, f"a whole number in [1, {MAX_ARMS}]")
        if not 1 <= arm_count <= MAX_ARMS:
            raise InvalidOption("arm_count", arm_count, f"a whole number in [1, {MAX_ARMS}]")
        self.arm_count = int(arm_count)
        self.spacing_m = real_number(
            spacing_m, "spacing_m", "a distance in [0.5, 5] m", low=0.5, high=5.0
        )
        self.tolerance_m = real_number(
            tolerance_m, "tolerance_m", "a distance in (0, 0.5] m", low=1e-6, high=0.5
        )
        self.success_bonus = real_number(
            success_bonus, "success_bonus", "a number in [0, 100]", low=0.0, high=100.0
        )
        self.target_region = TargetRegion.parse(target_region)
        self.limit_margin = limit_margin
        self.min_tool_height_m = min_tool_height_m
        self.arms = tuple(f"arm{i}" for i in range(self.arm_count))
        self.model = _model_reference(model)
        self._targets: dict[str, FloatArray] = {}
        #: Whether a configuration touches the arm or the floor (PyBullet client of its own).
        self._probe: ClearanceProbe | None = None

    @property
    def name(self) -> str:
        return f"reach with {self.arm_count} arm{'s' * (self.arm_count > 1)}"

    def spec(self) -> FleetSpec:
        arms = tuple(
            ArmSpec(name, self.model, SpawnPose(x=i * self.spacing_m, yaw_deg=FACING_DEG))
            for i, name in enumerate(self.arms)
        )
        return FleetSpec(WorldSpec(realtime=False, viewer=False), arms, source="reach task")

    @property
    def targets(self) -> dict[str, FloatArray]:
        """Each arm's target this episode: a 4x4 world pose of tool0."""
        return {name: pose.copy() for name, pose in self._targets.items()}

    def reset(self, world: World, rng: np.random.Generator) -> None:
        arms = [world.arm(name) for name in self.arms]
        if self.target_region is TargetRegion.NEAR:
            self._targets = {arm.name: self._near_target(world, arm.name, rng) for arm in arms}
            return
        if self._probe is None:  # one for every episode: making one costs ~20 ms
            self._probe = ClearanceProbe(arms[0])
            weakref.finalize(self, self._probe.close)
        drawn = draw_row_targets(
            arms, rng, 1, limit_margin=self.limit_margin,
            min_tool_height_m=self.min_tool_height_m, probe=self._probe,
        )  # fmt: skip
        self._targets = {name: targets[0].pose for name, targets in drawn.items()}

    def _near_target(self, world: World, arm: str, rng: np.random.Generator) -> FloatArray:
        """A ``"near"`` target of ``arm``: tool0's start pose moved within the cube."""
        target = world.tf.world_pose(world.arm(arm).description.tool0).copy()
        target[:3, 3] += rng.uniform(-NEAR_CUBE_M / 2, NEAR_CUBE_M / 2, 3)
        target[2, 3] = max(target[2, 3], self.min_tool_height_m)
        return target

    def arm_spaces(self, arm: str) -> dict[str, spaces.Box]:
        del arm
        bound = np.float32(2 * WORKSPACE_M)
        return {
            "target_pose": pose_space(),
            "target_offset": spaces.Box(-bound, bound, (3,), dtype=np.float32),
        }

    def observe(self, world: World, arm: str) -> dict[str, FloatArray]:
        target = self._targets[arm]
        tool = world.tf.world_pose(world.arm(arm).description.tool0)
        return {
            "target_pose": pose_vector(target),
            "target_offset": target[:3, 3] - tool[:3, 3],
        }

    def distances(self, world: World) -> dict[str, float]:
        """Each arm's tool0 distance to its target's position [m]."""
        return {
            name: float(
                np.linalg.norm(
                    world.tf.world_pose(world.arm(name).description.tool0)[:3, 3] - target[:3, 3]
                )
            )
            for name, target in self._targets.items()
        }

    def evaluate(self, world: World) -> Evaluation:
        distances = self.distances(world)
        success = all(d <= self.tolerance_m for d in distances.values())
        reward = -sum(min(d, DISTANCE_CAP_M) for d in distances.values())
        if success:
            reward += self.success_bonus
        return Evaluation(reward, success, {"distance_m": distances})

    def reward_bounds(self) -> tuple[float, float]:
        return (-DISTANCE_CAP_M * self.arm_count, self.success_bonus)


def _model_reference(model: object) -> str:
    """``model`` as a spec names it: a model file's path made absolute."""
    if isinstance(model, os.PathLike):
        model = os.fspath(model)
    if not isinstance(model, str) or not model:
        raise InvalidOption(
            "model", model, "a shipped model's name (armfleet models), or a model file's path"
        )
    if is_model_file(model) and not model.startswith("package://"):
        return str(Path(model).expanduser().absolute())
    return model
