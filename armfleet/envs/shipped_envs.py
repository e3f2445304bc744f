"""The registered environments: Reach, Handover and any spec as :class:`MultiArmEnv`
classes, so that ``gymnasium.make`` finds their metadata."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from armfleet.envs.actions import ActionKind
from armfleet.envs.multi_arm_env import MultiArmEnv
from armfleet.envs.registration import HANDOVER_MAX_STEPS, REACH_MAX_STEPS, SCENE_MAX_STEPS
from armfleet.envs.tasks.handover_task import HandoverTask, RewardKind
from armfleet.envs.tasks.reach_task import SUCCESS_BONUS, ReachTask, TargetRegion
from armfleet.envs.tasks.task import SceneTask
from armfleet.scenarios.handover import TOLERANCE_M
from armfleet.scenarios.reach import MODEL
from armfleet.spec import FleetSpec


class ReachEnv(MultiArmEnv):
    """``armfleet/Reach-v0``: ``arm_count`` arms (Pandas unless ``model`` names another)
    reach random targets (:class:`~armfleet.envs.tasks.ReachTask`); joint-delta actions by
    default.

    Args:
        arm_count, spacing_m, tolerance_m, model, success_bonus, target_region: of the
            task (``model``: a shipped model, one's own by name, or a model file;
            ``target_region``: ``"workspace"`` or ``"near"``).
        **options: of :class:`MultiArmEnv`.
    """

    def __init__(
        self,
        arm_count: int = 1,
        spacing_m: float = 1.0,
        tolerance_m: float = 0.02,
        model: str | os.PathLike[str] = MODEL,
        success_bonus: float = SUCCESS_BONUS,
        target_region: TargetRegion | str = TargetRegion.WORKSPACE,
        **options: Any,
    ) -> None:
        options.setdefault("action_kind", ActionKind.JOINT_DELTAS)
        options.setdefault("max_episode_steps", REACH_MAX_STEPS)
        task = ReachTask(
            arm_count, spacing_m, tolerance_m, model=model, success_bonus=success_bonus,
            target_region=target_region,
        )  # fmt: skip
        super().__init__(task, **options)


class HandoverEnv(MultiArmEnv):
    """``armfleet/Handover-v0``: bob hands the bar to toby, who puts it on the mat
    (:class:`~armfleet.envs.tasks.HandoverTask`); tool-delta actions by default.

    Args:
        reward: ``"dense"`` or ``"sparse"``.
        tolerance_m: of the task's success [m].
        spec: the scene (``handover`` by default).
        **options: of :class:`MultiArmEnv`.
    """

    def __init__(
        self,
        reward: RewardKind | str = RewardKind.DENSE,
        tolerance_m: float = TOLERANCE_M,
        spec: FleetSpec | str | Path = "handover",
        **options: Any,
    ) -> None:
        options.setdefault("action_kind", ActionKind.TOOL_DELTA)
        options.setdefault("max_episode_steps", HANDOVER_MAX_STEPS)
        super().__init__(HandoverTask(reward, tolerance_m, spec), **options)


class SceneEnv(MultiArmEnv):
    """``armfleet/Scene-v0``: the arms of any launch spec, reward 0, no success
    (:class:`~armfleet.envs.tasks.SceneTask`); joint-delta actions by default.

    Args:
        spec: a spec, a path, or a shipped spec's name (``bob_and_toby`` by default).
        **options: of :class:`MultiArmEnv`.
    """

    def __init__(self, spec: FleetSpec | str | Path = "bob_and_toby", **options: Any) -> None:
        options.setdefault("max_episode_steps", SCENE_MAX_STEPS)
        super().__init__(SceneTask(spec), **options)
