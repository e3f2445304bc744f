"""Time a joint path within every joint's velocity, acceleration and jerk limits.

A planned path is a polyline in joint space, each segment proven clear. A timed path is
a chain of segments, one per pair of waypoints, each reaching its waypoint exactly:
:class:`TimedSegments` samples and evaluates any such chain.

:class:`TimedPath` is the reference timing, rest to rest: along each segment the joints
move in a straight line, ``q(t) = a + s(t) (b - a)``, with ``s`` going from 0 to 1 at
rest at both ends, timed by Ruckig (jerk-limited, time-optimal) with the limits of the
joint that binds: ``s' <= v_i / |b_i - a_i|``, and likewise for acceleration and jerk.
Every joint keeps its own limits exactly and nothing leaves the checked polyline, at
the cost of a stop at every waypoint. Planned motions pass through their waypoints
without stopping (:class:`~armfleet.planning.smooth_timing.SmoothPath`); this one is
kept to compare against, and for the segments a smooth path takes straight.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import ruckig

from armfleet.controllers.jerk_limited_trajectory import SampledMotion, TrajectoryError, calculate
from armfleet.messages import FloatArray
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.scene import CollisionChecker

Kinematics = tuple[FloatArray, FloatArray, FloatArray]


@dataclass(frozen=True)
class JointLimits:
    """Per joint of a state: velocity [rad/s], acceleration [rad/s^2], jerk [rad/s^3]."""

    velocity: FloatArray
    acceleration: FloatArray
    jerk: FloatArray


class Segment(Protocol):
    """The motion from one waypoint to the next."""

    @property
    def duration(self) -> float: ...

    def at(self, times: FloatArray) -> Kinematics:
        """Positions, velocities and accelerations (rows) at ``times`` after its start."""
        ...


class StraightSegment:
    """Rest to rest along the straight line from ``start`` to ``end``.

    Args:
        start, end: the waypoints.
        limits: the joints' limits (the joint that binds sets the timing).
    """

    def __init__(self, start: FloatArray, end: FloatArray, limits: JointLimits) -> None:
        self._start = start
        self._delta = end - start
        self._timing = _straight_timing(np.abs(self._delta), limits)

    @property
    def duration(self) -> float:
        return float(self._timing.duration)

    def at(self, times: FloatArray) -> Kinematics:
        timing = self._timing
        s, ds, dds = np.array([[x[0] for x in timing.at_time(float(t))] for t in times]).T
        delta = self._delta
        return (
            self._start + np.clip(s, 0.0, 1.0)[:, None] * delta,
            ds[:, None] * delta,
            dds[:, None] * delta,
        )


class TimedSegments:
    """A chain of timed segments through waypoints, from rest to rest.

    Args:
        waypoints: states (rows), the first where the arms are now (at rest).
        segments: one per pair of consecutive waypoints, each ending at the next.
    """

    def __init__(self, waypoints: FloatArray, segments: list[Segment]) -> None:
        self.waypoints = np.asarray(waypoints, dtype=float)
        self._segments = segments
        #: Time each waypoint is reached [s].
        self.times = np.concatenate([[0.0], np.cumsum([s.duration for s in segments])])

    @property
    def duration(self) -> float:
        """Time from the first waypoint to the last [s]."""
        return float(self.times[-1])

    @property
    def segments(self) -> list[Segment]:
        return list(self._segments)

    def sample(self, period: float) -> SampledMotion:
        """The motion one row per ``period`` after the start, the last row the goal at rest."""
        steps = max(1, math.ceil(self.duration / period - 1e-9))
        times = np.minimum(np.arange(1, steps + 1) * period, self.duration)
        position, velocity, acceleration = self.at(times)
        position[-1], velocity[-1], acceleration[-1] = self.waypoints[-1], 0.0, 0.0
        return SampledMotion(position, velocity, acceleration)

    def at(self, times: FloatArray) -> Kinematics:
        """Positions, velocities and accelerations (rows) at ``times`` [s], clamped to the path."""
        times = np.clip(np.asarray(times, dtype=float), 0.0, self.duration)
        n = self.waypoints.shape[1]
        position = np.empty((times.size, n))
        velocity = np.zeros((times.size, n))
        acceleration = np.zeros((times.size, n))
        if not self._segments:
            position[:] = self.waypoints[0]
            return position, velocity, acceleration
        segment = np.clip(np.searchsorted(self.times, times, side="right") - 1, 0, None)
        segment = np.minimum(segment, len(self._segments) - 1)
        for index in np.unique(segment):
            rows = np.flatnonzero(segment == index)
            local = times[rows] - self.times[index]
            position[rows], velocity[rows], acceleration[rows] = self._segments[index].at(local)
        return position, velocity, acceleration

    def first_unclear(self, checker: CollisionChecker) -> FloatArray | None:
        """A state of the motion ``checker`` does not prove clear, or None (the motion as
        it is executed is proven contact-free)."""
        failure = PathCertifier(checker).first_failure(self.waypoints)
        return None if failure is None else failure[1]


class TimedPath(TimedSegments):
    """The reference timing: a polyline timed segment by segment, rest to rest.

    Args:
        waypoints: states (rows), the first where the arms are now (at rest).
        limits: the joints' limits.
    """

    def __init__(self, waypoints: FloatArray, limits: JointLimits) -> None:
        points = np.asarray(waypoints, dtype=float)
        segments: list[Segment] = [
            StraightSegment(a, b, limits) for a, b in itertools.pairwise(points)
        ]
        super().__init__(points, segments)


def _straight_timing(span: FloatArray, limits: JointLimits) -> ruckig.Trajectory:
    """Ruckig's rest-to-rest timing of ``s`` from 0 to 1 along a segment moving each joint
    by ``span``, limited by the joint that binds."""
    moving = span > 1e-12
    timing = ruckig.Trajectory(1)
    path = ruckig.InputParameter(1)
    path.current_position, path.target_position = [0.0], [1.0 if moving.any() else 0.0]
    if moving.any():
        path.max_velocity = [float(np.min(limits.velocity[moving] / span[moving]))]
        path.max_acceleration = [float(np.min(limits.acceleration[moving] / span[moving]))]
        path.max_jerk = [float(np.min(limits.jerk[moving] / span[moving]))]
    else:
        path.max_velocity, path.max_acceleration, path.max_jerk = [1.0], [1.0], [1.0]
    result = calculate(ruckig.Ruckig(1), path, timing)
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise TrajectoryError(f"Ruckig cannot time a path segment: {result}")
    return timing
