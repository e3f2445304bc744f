"""A saved state of a whole world, restored in a millisecond instead of launching anew.

A :class:`WorldSnapshot` (``world.snapshot()``) keeps

- the physics: PyBullet's ``saveState`` (positions, velocities and the contact points it
  warm-starts from, so that the steps after a restore are those after the save, bit for
  bit), plus each arm's joint motors (brakes or torque mode), which ``saveState`` leaves out;
- everything of armfleet's (:class:`~armfleet.world.object_state.ObjectState`): controllers,
  trajectories (Ruckig's compiled solvers are put in one fixed form,
  :meth:`~armfleet.controllers.jerk_limited_trajectory.JerkLimitedTrajectory.on_restored`),
  grippers and what they hold, objects, simulated time, the bus (subscriptions and the
  last message of every topic), the TF tree, the contact bookkeeping and the safety state.

What a snapshot does not keep is the world's machinery, left as it is: the model library,
the front ends attached (viewer, Foxglove), the planner and its threads, requests other
threads submitted, the step guard, and the wall time spent stepping.

Two restores of one snapshot are followed by the same steps, bit for bit, whatever ran
between them, as long as the world is made of the same things: a restore refuses
(:class:`SnapshotStale`, the world unchanged) if an arm, an object, a PyBullet body or
constraint, or a front end was added or removed since the save, or if the world is closed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import pybullet as p

from armfleet.errors import ArmfleetError
from armfleet.world.object_state import ObjectState

if TYPE_CHECKING:
    from armfleet.physics.arm_body import ArmBody
    from armfleet.world import World


class SnapshotStale(ArmfleetError):
    """A snapshot that no longer fits its world (see the module docstring)."""

    def __init__(self, reason: str) -> None:
        self.reason = reason
        super().__init__(
            f"cannot restore this world snapshot: {reason}; a snapshot restores a world "
            "made of the same arms, objects, bodies and front ends as when it was taken"
        )


class WorldSnapshot:
    """The state of ``world`` now (see the module docstring); made by :meth:`World.snapshot`.

    Args:
        world: the world, open, not inside a step.
        keep: the world's machinery, left as it is by :meth:`restore`.
        keep_attributes: the world's own attributes left as they are.

    Raises:
        UnsavedState: some state is out of reach (a compiled object of an unknown type).
    """

    def __init__(
        self, world: World, keep: tuple[object, ...], keep_attributes: tuple[str, ...]
    ) -> None:
        self._world = world
        self._client = world.physics_client
        self._structure = _structure(world)
        self._motors: list[tuple[ArmBody, bool]] = [
            (arm.body, arm.body.torque_mode) for arm in world.arms.values()
        ]
        self._python = ObjectState(world, keep=keep, keep_attributes=keep_attributes)
        self._physics = p.saveState(physicsClientId=self._client)
        self._time = world.time

    @property
    def time(self) -> float:
        """The world's simulated time when the snapshot was taken [s]."""
        return self._time

    @property
    def object_count(self) -> int:
        """Python objects whose state the snapshot keeps (for the curious)."""
        return self._python.object_count

    def restore(self) -> None:
        """Put the world back as it was when the snapshot was taken.

        Call it from the thread that steps the world, between steps.

        Raises:
            SnapshotStale: the world is closed, or made of other things now; it is unchanged.
            WorldBusy: called from inside a step, or while another thread steps the world.
        """
        world = self._world
        if world.closed:
            raise SnapshotStale("the world is closed")
        now = _structure(world)
        if now != self._structure:
            raise SnapshotStale(_difference(self._structure, now))
        with world.step_guard.owned("restore"):
            p.restoreState(self._physics, physicsClientId=self._client)
            for body, torque_mode in self._motors:
                if torque_mode:
                    body.release_brakes()
                else:
                    body.engage_brakes()
            self._python.restore()  # after the motors: their Python side as saved

    def __repr__(self) -> str:
        return f"WorldSnapshot(time={self._time:.3f} s, objects={self.object_count})"


class _Structure(NamedTuple):
    """What a world is made of: arms and objects (name, identity), PyBullet bodies (ids)
    and constraints (count), front ends (count)."""

    arms: tuple[tuple[str, int], ...]
    objects: tuple[tuple[str, int], ...]
    bodies: tuple[int, ...]
    constraints: int
    front_ends: int


def _structure(world: World) -> _Structure:
    client = world.physics_client
    bodies = tuple(
        p.getBodyUniqueId(i, physicsClientId=client)
        for i in range(p.getNumBodies(physicsClientId=client))
    )
    return _Structure(
        tuple((name, id(arm)) for name, arm in world.arms.items()),
        tuple((name, id(obj)) for name, obj in world.objects.items()),
        bodies,
        p.getNumConstraints(physicsClientId=client),
        world.listener_count,
    )


def _difference(saved: _Structure, now: _Structure) -> str:
    """The first difference of two structures, in words."""
    for label, was, is_now in (
        ("arms", saved.arms, now.arms),
        ("objects", saved.objects, now.objects),
    ):
        if was != is_now:
            return f"its {label} were {[n for n, _ in was]}, now {[n for n, _ in is_now]}"
    counts = (
        ("PyBullet bodies", len(saved.bodies), len(now.bodies)),
        ("PyBullet constraints", saved.constraints, now.constraints),
        ("front ends", saved.front_ends, now.front_ends),
    )
    for label, before, after in counts:
        if before != after:
            return f"its {label} were {before}, now {after}"
    return f"its PyBullet bodies were {list(saved.bodies)}, now {list(now.bodies)}"
