"""Time a joint path within every joint's velocity, acceleration and jerk limits.

A planned path is a polyline in joint space, each segment proven clear. The
motion follows it exactly: along each segment the joints move in a straight line,
``q(t) = a + s(t) (b - a)``, with ``s`` going from 0 to 1 at rest at both ends,
timed by Ruckig (jerk-limited, time-optimal) with the limits of the joint that
binds: ``s' <= v_i / |b_i - a_i|``, and likewise for acceleration and jerk. Every
joint then keeps its own limits exactly, the arms of a joint plan start on the same
step and arrive at the same instant, and nothing leaves the checked polyline.

Stopping at each waypoint costs time against blending the corners; it keeps the
proof of clearance intact (a blended corner leaves the checked segments).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import ruckig

from armfleet.controllers.jerk_limited_trajectory import SampledMotion, TrajectoryError, calculate
from armfleet.messages import FloatArray


@dataclass(frozen=True)
class JointLimits:
    """Per joint of a state: velocity [rad/s], acceleration [rad/s^2], jerk [rad/s^3]."""

    velocity: FloatArray
    acceleration: FloatArray
    jerk: FloatArray


class TimedPath:
    """A polyline of joint states, timed segment by segment.

    Args:
        waypoints: states (rows), the first where the arms are now (at rest).
        limits: the joints' limits.
    """

    def __init__(self, waypoints: FloatArray, limits: JointLimits) -> None:
        self.waypoints = np.asarray(waypoints, dtype=float)
        self._segments: list[ruckig.Trajectory] = []
        starts = [0.0]
        for a, b in zip(self.waypoints[:-1], self.waypoints[1:], strict=True):
            timing = _segment_timing(np.abs(b - a), limits)
            self._segments.append(timing)
            starts.append(starts[-1] + float(timing.duration))
        #: Time each waypoint is reached [s].
        self.times = np.array(starts)

    @property
    def duration(self) -> float:
        """Time from the first waypoint to the last [s]."""
        return float(self.times[-1])

    def sample(self, period: float) -> SampledMotion:
        """The motion one row per ``period`` after the start, the last row the goal at rest."""
        steps = max(1, math.ceil(self.duration / period - 1e-9))
        times = np.minimum(np.arange(1, steps + 1) * period, self.duration)
        position, velocity, acceleration = self.at(times)
        position[-1], velocity[-1], acceleration[-1] = self.waypoints[-1], 0.0, 0.0
        return SampledMotion(position, velocity, acceleration)

    def at(self, times: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions, velocities and accelerations (rows) at ``times`` [s], clamped to the path."""
        times = np.clip(np.asarray(times, dtype=float), 0.0, self.duration)
        n = self.waypoints.shape[1]
        position = np.empty((times.size, n))
        velocity = np.empty((times.size, n))
        acceleration = np.empty((times.size, n))
        segment = np.clip(np.searchsorted(self.times, times, side="right") - 1, 0, None)
        segment = np.minimum(segment, len(self._segments) - 1) if self._segments else segment
        if not self._segments:
            position[:] = self.waypoints[0]
            velocity[:] = acceleration[:] = 0.0
            return position, velocity, acceleration
        for index in np.unique(segment):
            rows = np.flatnonzero(segment == index)
            timing = self._segments[int(index)]
            local = times[rows] - self.times[index]
            s, ds, dds = np.array([[x[0] for x in timing.at_time(float(t))] for t in local]).T
            a, b = self.waypoints[index], self.waypoints[index + 1]
            delta = b - a
            position[rows] = a + np.clip(s, 0.0, 1.0)[:, None] * delta
            velocity[rows] = ds[:, None] * delta
            acceleration[rows] = dds[:, None] * delta
        return position, velocity, acceleration


def _segment_timing(span: FloatArray, limits: JointLimits) -> ruckig.Trajectory:
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
