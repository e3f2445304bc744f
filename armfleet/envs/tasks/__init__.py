"""Tasks of the learning environments: a scene, what is drawn at reset, reward, success."""

from armfleet.envs.tasks.handover_task import HandoverTask, RewardKind
from armfleet.envs.tasks.reach_task import ReachTask, TargetRegion
from armfleet.envs.tasks.task import Evaluation, SceneTask, Task

__all__ = [
    "Evaluation",
    "HandoverTask",
    "ReachTask",
    "RewardKind",
    "SceneTask",
    "TargetRegion",
    "Task",
]
