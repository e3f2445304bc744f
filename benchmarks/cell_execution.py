"""Running motions in a world of the shared cell and watching, in PyBullet, what they touch.

What a benchmark of planned motions needs around a :class:`armfleet.World`:

- :class:`ContactLog`: the contacts on ``/collisions`` that involve an arm (with
  another arm, itself, the floor, a static object or a movable cube), per motion;
- :func:`run_until_still`: run the world until its arms' motions have ended;
- :func:`respawn_at`: put the arms at a given start through the public API (take
  them out, put back any movable object that was pushed, bring them up again at
  those joint positions), so a motion that collided leaves nothing behind.
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from armfleet.world.launch import add_from_spec, spawn_from_spec
from armfleet.messages import CollisionReport, FloatArray
from armfleet.spec import FleetSpec

#: A movable object further than this from where the spec put it is put back [m].
MOVED_M = 1e-3
#: Simulated time run past a motion's planned end [s].
SETTLE_S = 0.02


@dataclass
class Touches:
    """The contacts of one motion that involve an arm.

    Attributes:
        steps: physics steps with at least one such contact.
        pairs: the link pairs (or link / object) that touched.
        deepest_m: deepest penetration seen [m].
    """

    steps: int = 0
    pairs: set[tuple[str, str]] = field(default_factory=set)
    deepest_m: float = 0.0

    @property
    def touched(self) -> bool:
        return self.steps > 0


class ContactLog:
    """Collects, from ``/collisions``, the contacts in which an arm of ``world`` takes part.

    Contacts between objects (a cube resting on the table) concern no arm and are left
    out; an arm against a movable cube counts.

    Args:
        world: the world to watch; its arm names are read when each report arrives.
    """

    def __init__(self, world: armfleet.World) -> None:
        self._world = world
        self._current = Touches()
        world.bus.subscribe("/collisions", self._on_report)

    def _on_report(self, report: CollisionReport) -> None:
        arms = self._world.arms
        hits = [c for c in report.contacts if c.body_a in arms or c.body_b in arms]
        if not hits:
            return
        self._current.steps += 1
        self._current.pairs.update(c.pair for c in hits)
        self._current.deepest_m = max(self._current.deepest_m, *(c.depth for c in hits))

    def take(self) -> Touches:
        """The contacts since the last call, and start counting afresh."""
        taken, self._current = self._current, Touches()
        return taken


def run_until_still(world: armfleet.World, duration_s: float) -> None:
    """Run ``world`` until none of its arms moves, at least ``duration_s`` +
    :data:`SETTLE_S` (the motion's planned length) and at most 1 s more.

    An arm in protective stop does not move: a motion that collided ends early.
    """
    world.run(max(0.0, duration_s) + SETTLE_S)
    for _ in range(50):
        if not any(arm.is_moving for arm in world.arms.values()):
            return
        world.run(SETTLE_S)


def respawn_at(world: armfleet.World, spec: FleetSpec, starts: Mapping[str, FloatArray]) -> None:
    """Bring every arm of ``spec`` up again in ``world`` at ``starts`` (joint positions by
    arm name), after putting back any movable object a previous motion pushed.

    Raises:
        ArmfleetError: the world refuses an arm at its start (e.g. StartPoseCollision).
    """
    for name in list(world.arms):
        world.remove(name)
    for obj in spec.objects:
        present = world.objects.get(obj.name)
        if present is None or present.is_static:
            continue
        moved = float(np.linalg.norm(present.pose[:3, 3] - np.array(obj.at)))
        if moved > MOVED_M:
            world.remove_object(obj.name)
            add_from_spec(world, obj)
    for arm in spec.arms:
        start = tuple(float(v) for v in starts[arm.name])
        spawn_from_spec(world, dataclasses.replace(arm, initial_positions=start))
