"""A planned motion of one arm or several: what it is and what it cost."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from armfleet.controllers.jerk_limited_trajectory import SampledMotion
from armfleet.messages import FloatArray
from armfleet.planning.path_timing import TimedSegments
from armfleet.planning.scene_pool import SceneSnapshot


@dataclass(frozen=True)
class Plan:
    """A collision-free motion, not yet executed (``world.execute(plan)`` runs it).

    Attributes:
        arms: the planned arms, in the order of a state.
        joint_names: per arm, its controlled joints (the columns of :meth:`path`).
        waypoints: the joint path (rows: states of every planned arm, concatenated);
            the motion passes through each without stopping (``timing``).
        duration_s: from the start of the execution to the arrival [s], the start
            delay included.
        start_delay_s: time the arms wait at the start for a moving arm to pass [s].
        planning_time_s: wall time of the whole request (IK, scene, search,
            simplification, proof, timing) [s].
        collision_checks: states checked for collision.
        samples: states the search sampled (0 when the straight line was clear).
        seconds: wall time per phase [s] (``ik``, ``scene``, ``check``, ``search``,
            ``simplify``, ``certify``, ``timing``, ``in_time``).
        clearance_m: the margin kept between different bodies [m].
        stamp: simulated time when it was planned [s]; executing later checks it again.
        timing: the timed path (positions at any time of the motion).
        scene: the world it was planned against (where every arm and object was).
        sampled: ``timing`` sampled at its arms' controller periods [s] (made with the
            plan, off the stepping thread; :meth:`motion` samples other periods).
    """

    arms: tuple[str, ...]
    joint_names: dict[str, tuple[str, ...]]
    waypoints: FloatArray
    duration_s: float
    start_delay_s: float
    planning_time_s: float
    collision_checks: int
    samples: int
    clearance_m: float
    stamp: float
    timing: TimedSegments
    seconds: dict[str, float] = field(default_factory=dict)
    scene: SceneSnapshot | None = field(default=None, repr=False, compare=False)
    sampled: dict[float, SampledMotion] = field(default_factory=dict, repr=False, compare=False)

    def motion(self, period: float) -> SampledMotion:
        """Every planned joint's reference, one row per ``period`` [s] of the motion."""
        sampled = self.sampled.get(period)
        return sampled if sampled is not None else self.timing.sample(period)

    def columns(self, arm: str) -> slice:
        """Where ``arm``'s joints are in a state."""
        offset = 0
        for name in self.arms:
            size = len(self.joint_names[name])
            if name == arm:
                return slice(offset, offset + size)
            offset += size
        raise KeyError(arm)

    def path(self, arm: str) -> FloatArray:
        """``arm``'s waypoints (rows, one column per joint of ``joint_names[arm]``)."""
        return np.array(self.waypoints[:, self.columns(arm)])

    @property
    def length_rad(self) -> float:
        """Joint-space length of the path [rad]."""
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)))

    def __repr__(self) -> str:
        return (
            f"Plan({' + '.join(self.arms)}: {len(self.waypoints)} waypoints, "
            f"{self.duration_s:.3f} s, planned in {self.planning_time_s * 1000:.1f} ms, "
            f"{self.collision_checks} collision checks)"
        )
