"""Learning environments on armfleet worlds: Gymnasium and PettingZoo (docs/envs.md).

>>> import gymnasium as gym
>>> import armfleet.envs
>>> env = gym.make("armfleet/Reach-v0", arm_count=2)
>>> flat = gym.make("armfleet/Reach-v0", flat=True)  # Box spaces, for Stable-Baselines3

Importing this package registers ``armfleet/Reach-v0``, ``armfleet/Handover-v0`` and
``armfleet/Scene-v0`` (any launch spec); ``import armfleet`` alone does not load it (nor
Gymnasium).

Rule: a front end (the ``envs`` extra: Gymnasium, PettingZoo); imports the world,
the scenarios and the core below; nothing but the CLI imports it.
"""

from armfleet.checks.extras import require_extra

require_extra("The learning environments", "envs", "gymnasium", "pettingzoo")


from armfleet.envs.actions import ActionKind, StepLimits
from armfleet.envs.arm_commander import ArmCommander
from armfleet.envs.errors import EnvError, EnvNotReset, InvalidAction, InvalidOption
from armfleet.envs.flat_spaces import FlatSpaces
from armfleet.envs.multi_arm_env import MultiArmEnv
from armfleet.envs.parallel_env import MultiArmParallelEnv
from armfleet.envs.registration import HANDOVER_ID, REACH_ID, SCENE_ID, register_envs
from armfleet.envs.rendering import RenderMode
from armfleet.envs.shipped_envs import HandoverEnv, ReachEnv, SceneEnv
from armfleet.envs.stop_policy import StopPolicy
from armfleet.envs.tasks import (
    Evaluation,
    HandoverTask,
    ReachTask,
    RewardKind,
    SceneTask,
    TargetRegion,
    Task,
)

register_envs()

__all__ = [
    "HANDOVER_ID",
    "REACH_ID",
    "SCENE_ID",
    "ActionKind",
    "ArmCommander",
    "EnvError",
    "EnvNotReset",
    "Evaluation",
    "FlatSpaces",
    "HandoverEnv",
    "HandoverTask",
    "InvalidAction",
    "InvalidOption",
    "MultiArmEnv",
    "MultiArmParallelEnv",
    "ReachEnv",
    "ReachTask",
    "RenderMode",
    "RewardKind",
    "SceneEnv",
    "SceneTask",
    "StepLimits",
    "StopPolicy",
    "TargetRegion",
    "Task",
    "register_envs",
]
