"""Handover: bob picks a bar from his table and hands it to toby, who puts it on the mat.

The scene is ``launch_specs/handover.yaml`` (or another spec with the same arms and
objects). At reset the bar is moved on its table by up to :data:`BAR_SHIFT_M` along x and
y and turned by up to :data:`BAR_TURN_DEG` about z, drawn with the episode's generator.

The goal is the bar resting on the mat: its centre within ``tolerance_m`` of the mat's
centre lifted by half the mat and half the bar, moving slower than
:data:`RESTING_SPEED_M_S`, held by neither gripper. Rewards (chosen at construction):

- sparse: 1 on success, else 0;
- dense: ``-d_goal - 0.5 d_reach + 0.1 held`` with ``d_goal`` the bar centre's distance to
  the goal [m], ``d_reach`` the distance from the nearer tcp (between the finger pads) to
  the bar's centre [m], each capped at :data:`DISTANCE_CAP_M` (a step's reward is then
  bounded), ``held`` 1 while a gripper holds something. Moving the bar
  straight towards the goal by ``s`` raises it by at least ``0.5 s``, whatever the arms do
  (``d_reach`` changes by at most ``s``).
"""

from __future__ import annotations

import enum
import math
from pathlib import Path

import numpy as np

from armfleet.checks.real_numbers import real_number
from armfleet.envs.choices import choose
from armfleet.envs.errors import InvalidOption
from armfleet.envs.tasks.task import Evaluation, Task
from armfleet.messages import FloatArray
from armfleet.scenarios.handover import MAT_TO_BAR_CENTRE_M, TOLERANCE_M
from armfleet.spec import FleetSpec, load_spec
from armfleet.world import World

ARMS = ("bob", "toby")
BAR, MAT = "bar", "mat"
#: Largest shift of the bar's start along x and y [m], and turn about z [deg].
BAR_SHIFT_M, BAR_TURN_DEG = 0.02, 10.0
#: A bar slower than this is at rest [m/s].
RESTING_SPEED_M_S = 0.01
#: Weights of the dense reward's reach and hold terms.
REACH_WEIGHT, HOLD_BONUS = 0.5, 0.1
#: The dense reward's distances are capped here [m] (the scene is ~1.5 m across).
DISTANCE_CAP_M = 3.0


class RewardKind(enum.Enum):
    """The Handover reward."""

    DENSE = "dense"
    SPARSE = "sparse"

    @classmethod
    def parse(cls, value: object) -> RewardKind:
        return choose(cls, value, "reward")


class HandoverTask(Task):
    """Bob hands the bar to toby, who puts it on the mat (see the module docstring).

    Args:
        reward: ``"dense"`` or ``"sparse"``.
        tolerance_m: largest distance of the bar's centre from the goal at success [m].
        spec: the scene; ``handover`` (the shipped spec) by default. It must have the
            arms bob and toby, with grippers, and the objects ``bar`` and ``mat``.
    """

    def __init__(
        self,
        reward: RewardKind | str = RewardKind.DENSE,
        tolerance_m: float = TOLERANCE_M,
        spec: FleetSpec | str | Path = "handover",
    ) -> None:
        self.reward = RewardKind.parse(reward)
        self.tolerance_m = real_number(
            tolerance_m, "tolerance_m", "a distance in (0, 0.5] m", low=1e-6, high=0.5
        )
        self._spec = spec if isinstance(spec, FleetSpec) else load_spec(spec)
        arms = [arm.name for arm in self._spec.arms]
        objects = [obj.name for obj in self._spec.objects]
        if not set(ARMS) <= set(arms) or not {BAR, MAT} <= set(objects):
            raise InvalidOption(
                "spec", self._spec.source, "a scene with the arms bob and toby and the objects "
                f"bar and mat (this one has arms {arms}, objects {objects})",
            )  # fmt: skip

    @property
    def name(self) -> str:
        return f"handover ({self.reward.value} reward)"

    def spec(self) -> FleetSpec:
        return self._spec

    def reset(self, world: World, rng: np.random.Generator) -> None:
        bar = world.object(BAR)
        pose = bar.pose
        shift = rng.uniform(-BAR_SHIFT_M, BAR_SHIFT_M, 2)
        yaw = math.degrees(math.atan2(pose[1, 0], pose[0, 0])) + rng.uniform(
            -BAR_TURN_DEG, BAR_TURN_DEG
        )
        bar.set_pose((pose[0, 3] + shift[0], pose[1, 3] + shift[1], pose[2, 3]), (0.0, 0.0, yaw))

    @staticmethod
    def goal(world: World) -> FloatArray:
        """Where the bar's centre rests on the mat's centre [m]."""
        goal: FloatArray = world.tf.world_pose(MAT)[:3, 3].copy()
        goal[2] += MAT_TO_BAR_CENTRE_M
        return goal

    def evaluate(self, world: World) -> Evaluation:
        bar = world.object(BAR)
        centre = bar.position
        to_goal = float(np.linalg.norm(centre - self.goal(world)))
        reach = min(
            float(np.linalg.norm(world.tf.world_pose(f"{name}_tcp")[:3, 3] - centre))
            for name in ARMS
        )
        held = any(world.arm(name).gripper.holding for name in ARMS)
        resting = float(np.linalg.norm(bar.velocity)) < RESTING_SPEED_M_S
        success = to_goal <= self.tolerance_m and resting and not held
        if self.reward is RewardKind.SPARSE:
            reward = float(success)
        else:
            reward = (
                -min(to_goal, DISTANCE_CAP_M)
                - REACH_WEIGHT * min(reach, DISTANCE_CAP_M)
                + HOLD_BONUS * held
            )
        info: dict[str, object] = {"bar_to_goal_m": to_goal, "tcp_to_bar_m": reach, "held": held}
        return Evaluation(reward, success, info)

    def reward_bounds(self) -> tuple[float, float]:
        if self.reward is RewardKind.SPARSE:
            return (0.0, 1.0)
        return (-(1.0 + REACH_WEIGHT) * DISTANCE_CAP_M, HOLD_BONUS)
