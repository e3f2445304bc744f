"""Registers the shipped environments with Gymnasium (done by ``import armfleet.envs``).

In a process that has not imported ``armfleet.envs`` (a ``spawn``-ed vector worker),
name the module in the id and Gymnasium imports it:
``gymnasium.make("armfleet.envs:armfleet/Reach-v0")``.
"""

from __future__ import annotations

import gymnasium as gym

REACH_ID = "armfleet/Reach-v0"
HANDOVER_ID = "armfleet/Handover-v0"
SCENE_ID = "armfleet/Scene-v0"
#: Episode lengths [environment steps]: 4 s, 30 s and 20 s at the default 20 ms period.
REACH_MAX_STEPS = 200
HANDOVER_MAX_STEPS = 1500
SCENE_MAX_STEPS = 1000


def register_envs() -> None:
    """Register :data:`REACH_ID`, :data:`HANDOVER_ID` and :data:`SCENE_ID` (once; again
    does nothing)."""
    for env_id, entry_point, steps in (
        (REACH_ID, "armfleet.envs.shipped_envs:ReachEnv", REACH_MAX_STEPS),
        (HANDOVER_ID, "armfleet.envs.shipped_envs:HandoverEnv", HANDOVER_MAX_STEPS),
        (SCENE_ID, "armfleet.envs.shipped_envs:SceneEnv", SCENE_MAX_STEPS),
    ):
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, max_episode_steps=steps)
