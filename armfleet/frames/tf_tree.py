"""Transform lookup between any two frames of a world."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Protocol

import numpy as np

from armfleet.errors import UnknownFrame, WorldClosed
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray
from armfleet.runtime.lifetime import Lifetime, while_alive

WORLD_FRAME = "world"


class PosedFrame(Protocol):
    """A frame of the scene whose world pose is measured (a scene object)."""

    @property
    def pose(self) -> FloatArray:
        """4x4 pose in ``world`` [m]."""
        ...


class TfTree:
    """Looks up transforms from the arms' models at their latest measured state,
    and the scene objects' poses as measured after the last step.

    Args:
        arms: callable returning, per arm name, its kinematics and the current
            joint positions (read from the physics engine at the last step).
        objects: callable returning the scene objects by name (frame ``<object>``).
        lifetime: its world's; lookups raise :class:`~armfleet.errors.WorldClosed`
            once it has ended.
    """

    def __init__(
        self,
        arms: Callable[[], Mapping[str, tuple[ArmKinematics, FloatArray]]],
        objects: Callable[[], Mapping[str, PosedFrame]] | None = None,
        lifetime: Lifetime | None = None,
    ) -> None:
        self._arms = arms
        self._objects = objects
        self._lifetime = lifetime or Lifetime(WorldClosed)

    @property
    def lifetime(self) -> Lifetime:
        return self._lifetime

    @while_alive
    def world_pose(self, frame: str) -> FloatArray:
        """4x4 pose of ``frame`` in ``world``."""
        if frame == WORLD_FRAME:
            return np.eye(4)
        objects = self._objects() if self._objects is not None else {}
        text = isinstance(frame, str)  # a list is no frame name (nor a dictionary key)
        if text and frame in objects:
            return objects[frame].pose
        arms = self._arms()
        for kinematics, positions in arms.values():
            if text and kinematics.has_frame(frame):
                kinematics.update(positions)
                return kinematics.world_pose(frame)
        names = ", ".join(sorted(arms)) or "none yet"
        listed = ", ".join(sorted(objects)) or "none"
        raise UnknownFrame(
            frame,
            f"frames are 'world', the arms' prefixed links (arms: {names}; "
            f"e.g. <arm>_base_link, <arm>_tool0) and the objects ({listed})",
        )

    @while_alive
    def lookup(self, target_frame: str, source_frame: str) -> FloatArray:
        """Pose of ``source_frame`` in ``target_frame`` (4x4), as tf2's lookupTransform.

        ``lookup("world", "bob_tool0")`` is bob's flange in world coordinates.
        """
        target = self.world_pose(target_frame)
        source = self.world_pose(source_frame)
        return np.asarray(np.linalg.solve(target, source), dtype=np.float64)
