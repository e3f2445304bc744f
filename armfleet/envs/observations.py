"""What each arm observes: its joints, its tool, its gripper, the scene's objects and the
task's own entries. Every entry is a float32 ``Box``; values are clipped into it.

Per arm (a ``Dict``):

- ``joint_positions`` [rad]: bounded by the joint limits widened by
  :data:`JOINT_MARGIN_RAD` (an impact can push a joint a little past its limit);
- ``joint_velocities`` [rad/s]: bounded by :data:`VELOCITY_FACTOR` times the URDF limits;
- ``joint_targets`` [rad]: where the arm is being sent (the commander's joint target:
  deltas add to it, and a zero action keeps the arm going there), bounded by the joint
  limits. Without it the state is not observed: a jerk-limited motion lags its target
  by up to ~10 steps of the largest deltas;
- ``tool_pose``: tool0 in the world, (x, y, z, qx, qy, qz, qw) [m], qw >= 0;
- ``gripper_width`` [m] (arms with fingers, in tasks that use them): the measured opening;
- ``objects`` (worlds with objects): a ``Dict`` of each object's pose, as ``tool_pose``;
- the task's entries (Reach: ``target_pose``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from gymnasium import spaces

from armfleet.arms.arm import Arm
from armfleet.envs.poses import POSE_SIZE, pose_vector
from armfleet.messages import FloatArray
from armfleet.world import World

#: Joint positions are observed up to this far past the limits [rad].
JOINT_MARGIN_RAD = 0.1
#: Joint velocities are observed up to this multiple of the URDF velocity limits.
VELOCITY_FACTOR = 2.0
#: Positions are observed within this distance of the world origin [m].
WORKSPACE_M = 10.0
#: Gripper widths are observed up to this multiple of the widest opening.
WIDTH_FACTOR = 1.5


def pose_space() -> spaces.Box:
    """A pose vector: position within :data:`WORKSPACE_M`, quaternion components in [-1, 1]."""
    bound = np.array([WORKSPACE_M] * 3 + [1.0] * 4, dtype=np.float32)
    return spaces.Box(-bound, bound, (POSE_SIZE,), dtype=np.float32)


class ArmObserver:
    """Builds the observation space of one arm and its observations.

    Args:
        arm: the arm (of the world the space is made from; only its model is kept).
        objects: names of the scene's objects.
        task_entries: the task's entries for this arm, by name.
        gripper: observe the gripper's width (if the arm has fingers).
    """

    def __init__(
        self,
        arm: Arm,
        objects: list[str],
        task_entries: Mapping[str, spaces.Box],
        *,
        gripper: bool = True,
    ) -> None:
        self.name = arm.name
        lower, upper = arm.joint_limits
        velocity = arm.kinematics.velocity_limit[arm.kinematics.arm_indices] * VELOCITY_FACTOR
        entries: dict[str, spaces.Space[object]] = {
            "joint_positions": _box(lower - JOINT_MARGIN_RAD, upper + JOINT_MARGIN_RAD),
            "joint_velocities": _box(-velocity, velocity),
            "joint_targets": _box(lower, upper),
            "tool_pose": pose_space(),
        }
        self._has_gripper = gripper and arm.has_gripper
        if self._has_gripper:
            entries["gripper_width"] = _box([0.0], [arm.gripper.max_width * WIDTH_FACTOR])
        self._objects = list(objects)
        if objects:
            entries["objects"] = spaces.Dict({name: pose_space() for name in objects})
        entries.update(task_entries)
        self.space = spaces.Dict(entries)

    def observe(
        self, world: World, target: FloatArray, task_values: Mapping[str, FloatArray]
    ) -> dict[str, object]:
        """This arm's observation in ``world``, with its joint ``target`` [rad] and the
        task's values for it."""
        arm = world.arm(self.name)
        indices = arm.kinematics.arm_indices
        values: dict[str, object] = {
            "joint_positions": arm.body.position[indices],
            "joint_velocities": arm.body.velocity[indices],
            "joint_targets": target,
            "tool_pose": pose_vector(world.tf.world_pose(arm.description.tool0)),
        }
        if self._has_gripper:
            values["gripper_width"] = np.array([arm.gripper.width])
        if self._objects:
            values["objects"] = {
                name: pose_vector(world.object(name).pose) for name in self._objects
            }
        values.update(task_values)
        return _clipped(self.space, values)


def _box(low: object, high: object) -> spaces.Box:
    return spaces.Box(
        np.asarray(low, dtype=np.float32), np.asarray(high, dtype=np.float32), dtype=np.float32
    )


def _clipped(space: spaces.Dict, values: Mapping[str, object]) -> dict[str, object]:
    """``values`` as new float32 arrays inside ``space`` (nested for ``Dict`` entries)."""
    result: dict[str, object] = {}
    for key, entry in space.spaces.items():
        value = values[key]
        if isinstance(entry, spaces.Dict):
            assert isinstance(value, Mapping)
            result[key] = _clipped(entry, value)
        else:
            assert isinstance(entry, spaces.Box)
            array = np.asarray(value, dtype=np.float32)
            result[key] = np.clip(array, entry.low, entry.high).astype(np.float32)
    return result
