"""Planning scenes lent to one request at a time, so that requests can plan at once.

A :class:`~armfleet.planning.scene.PlanningScene` holds state (the configuration of every
arm, where the objects are, its checkers' geometry data), so two requests planning at
the same time, or the stepping thread re-checking a plan while another is searched, must
not share one. The world is read on the stepping thread into a :class:`SceneSnapshot`
(plain data: what the scene is made of, and where everything is); a request then takes
a scene of that make from the :class:`ScenePool` for as long as it plans, places
everything as the snapshot says, and gives it back. Scenes are built only when none of
that make is free (once per change of the world's arms, objects or held objects, and
once more per request planning at the same time), wherever the request runs.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from armfleet.messages import FloatArray
from armfleet.planning.scene import ArmGeometry, PlanningScene, SceneObject

#: Joint positions [rad or m] and placement entries that differ by less are the same. An arm
#: holding its pose after a motion still settles by up to ~1e-7 rad per step; 1e-6 rad
#: moves a Panda's geometry by at most ~3 µm (the sum of its joints' levers, ~3 m, times
#: it): nothing against the smallest clearance, 1 mm. A resting loose object (1e-5) is
#: not the same.
SAME_WITHIN = 1e-6


@dataclass(frozen=True)
class SceneParts:
    """What a scene is made of; equal ``key``\\ s make equal scenes.

    Attributes:
        key: the world's arms, objects and held objects, and the clearance.
        arms: the arms' geometries, in the world's order.
        objects: the scene objects (their placements are set per request).
        clearance_m: margin between different bodies [m].
    """

    key: tuple[Any, ...]
    arms: Sequence[ArmGeometry]
    objects: Sequence[SceneObject]
    clearance_m: float


@dataclass(frozen=True)
class SceneSnapshot:
    """The world at one step, as the planner sees it.

    Attributes:
        parts: what the scene is made of.
        arm_positions: per arm, every movable joint (its kinematics' order).
        object_placements: per object, its pose in the world, or in the frame of the
            hand joint that holds it.
    """

    parts: SceneParts
    arm_positions: Mapping[str, FloatArray]
    object_placements: Mapping[str, pin.SE3]

    def same_as(self, other: SceneSnapshot) -> bool:
        """Whether ``other`` is the same world, every arm and object where it is here to
        :data:`SAME_WITHIN` (a path proven against one is proven against the other)."""
        return (
            self.parts.key == other.parts.key
            and self.arm_positions.keys() == other.arm_positions.keys()
            and all(_same(q, other.arm_positions[name]) for name, q in self.arm_positions.items())
            and self.object_placements.keys() == other.object_placements.keys()
            and all(
                _same(placement.homogeneous, other.object_placements[name].homogeneous)
                for name, placement in self.object_placements.items()
            )
        )


class ScenePool:
    """Scenes of the world's latest make, each lent to one user at a time (thread-safe)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._key: tuple[Any, ...] | None = None
        self._free: list[PlanningScene] = []

    @contextlib.contextmanager
    def scene(self, snapshot: SceneSnapshot) -> Iterator[PlanningScene]:
        """A scene of ``snapshot``'s make, everything placed as it says, for this block
        only (built now if none is free)."""
        parts = snapshot.parts
        with self._lock:
            if self._key != parts.key:
                self._key, self._free = parts.key, []  # the world changed: older makes go
            scene = self._free.pop() if self._free else None
        if scene is None:
            scene = PlanningScene(parts.arms, parts.objects, parts.clearance_m)
        for name, positions in snapshot.arm_positions.items():
            scene.set_arm(name, positions)
        for name, placement in snapshot.object_placements.items():
            scene.set_object(name, placement)
        try:
            yield scene
        finally:
            with self._lock:
                if self._key == parts.key:
                    self._free.append(scene)

    @property
    def free(self) -> int:
        """Scenes built and not lent now."""
        return len(self._free)


def _same(a: FloatArray, b: FloatArray) -> bool:
    return bool(np.allclose(a, b, rtol=0.0, atol=SAME_WITHIN))
