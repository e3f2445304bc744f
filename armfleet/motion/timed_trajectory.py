"""Timed joint waypoints, as ROS's ``trajectory_msgs/JointTrajectory`` carries them,
checked and sampled once per controller period.

The interpolation is joint_trajectory_controller's, segment by segment from the
reference's present state (the first segment starts there, as the controller inserts
the current state when the first point is in the future):

- positions, velocities and accelerations given: a quintic per segment;
- positions and velocities: a cubic per segment;
- positions only: ros2_controllers interpolates linearly, with a velocity jump at
  every waypoint that the simulated arm would follow with a jolt (and that its
  acceleration limit refuses). Here the waypoints are joined by a cubic instead, with
  each inner waypoint's velocity the mean of its two neighbouring slopes (0 where the
  joint turns back) and rest at the last: the same points at the same times, smoothly.

The last point is a stop: its velocities and accelerations, when given, must be 0.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armfleet.controllers.jerk_limited_trajectory import SampledMotion
from armfleet.errors import ArmfleetError
from armfleet.messages import FloatArray

#: Times of waypoints, and rows of per-joint values (lists or arrays).
Times = Sequence[float] | FloatArray
Rows = Sequence[Sequence[float]] | FloatArray

#: Longest trajectory accepted [s]: a day of motion; longer is surely a unit mistake.
MAX_DURATION_S = 86_400.0
#: Most waypoints accepted in one trajectory.
MAX_POINTS = 100_000
#: A final velocity or acceleration below this counts as rest.
REST_TOLERANCE = 1e-9


class TrajectoryRefused(ArmfleetError):
    """A timed trajectory that cannot be followed as given; nothing moved."""

    def __init__(self, arm: str, problem: str) -> None:
        self.arm = arm
        super().__init__(f"{arm}: trajectory refused: {problem}")


@dataclass(frozen=True)
class TimedWaypoints:
    """Checked waypoints of one arm's joints.

    Attributes:
        times: (points,) time of each waypoint after the start [s], increasing, > 0.
        positions: (points, joints) [rad or m].
        velocities, accelerations: (points, joints), or None when not given.
    """

    times: FloatArray
    positions: FloatArray
    velocities: FloatArray | None
    accelerations: FloatArray | None

    @property
    def duration(self) -> float:
        return float(self.times[-1])


def check_waypoints(
    arm: str,
    joints: int,
    times: Times,
    positions: Rows,
    velocities: Rows | None = None,
    accelerations: Rows | None = None,
) -> TimedWaypoints:
    """The waypoints as arrays, or :class:`TrajectoryRefused` naming the first problem.

    Args:
        arm: the arm's name (for the messages).
        joints: how many joints each waypoint gives.
        times: each waypoint's time after the start [s].
        positions: per waypoint, one position per joint.
        velocities, accelerations: per waypoint, one per joint; None (or empty) when
            not given. Accelerations need velocities.
    """
    points = len(times)
    if points == 0:
        raise TrajectoryRefused(arm, "it has no points; give at least one")
    if points > MAX_POINTS:
        raise TrajectoryRefused(arm, f"{points} points; at most {MAX_POINTS}")
    stamps = _matrix(arm, "time_from_start", [[t] for t in times], points, 1)[:, 0]
    if stamps[0] <= 0.0:
        raise TrajectoryRefused(
            arm, f"the first point's time_from_start is {stamps[0]:.6g} s; it must be > 0"
        )
    steps = np.diff(stamps)
    if np.any(steps <= 0.0):
        index = int(np.argmax(steps <= 0.0)) + 1
        raise TrajectoryRefused(
            arm,
            f"point {index}'s time_from_start ({stamps[index]:.6g} s) is not after point "
            f"{index - 1}'s ({stamps[index - 1]:.6g} s); times must increase",
        )
    if stamps[-1] > MAX_DURATION_S:
        raise TrajectoryRefused(arm, f"it lasts {stamps[-1]:.6g} s; at most {MAX_DURATION_S:.0f} s")
    position = _matrix(arm, "positions", positions, points, joints)
    velocity = None
    if velocities is not None and not _empty(velocities):
        velocity = _matrix(arm, "velocities", velocities, points, joints)
    acceleration = None
    if accelerations is not None and not _empty(accelerations):
        acceleration = _matrix(arm, "accelerations", accelerations, points, joints)
    if acceleration is not None and velocity is None:
        raise TrajectoryRefused(arm, "accelerations are given without velocities; give both")
    for name, values in (("velocities", velocity), ("accelerations", acceleration)):
        if values is not None and np.any(np.abs(values[-1]) > REST_TOLERANCE):
            raise TrajectoryRefused(
                arm, f"the last point's {name} are not 0; a trajectory ends at rest"
            )
    return TimedWaypoints(stamps, position, velocity, acceleration)


def sample_waypoints(
    waypoints: TimedWaypoints,
    start: tuple[FloatArray, FloatArray, FloatArray],
    period: float,
) -> SampledMotion:
    """The motion through ``waypoints`` from ``start`` (position, velocity, acceleration
    of the reference now), one row per ``period`` [s], the last row the last point at rest.
    """
    knot_times = np.concatenate([[0.0], waypoints.times])
    knots = np.vstack([start[0], waypoints.positions])
    if waypoints.velocities is not None:
        slopes = np.vstack([start[1], waypoints.velocities])
    else:
        slopes = _inner_slopes(knot_times, knots, start[1])
    curvature = None
    if waypoints.accelerations is not None:
        curvature = np.vstack([start[2], waypoints.accelerations])
    steps = max(1, math.ceil(waypoints.duration / period - 1e-9))
    t = np.minimum(np.arange(1, steps + 1) * period, waypoints.duration)
    segment = np.clip(np.searchsorted(knot_times, t, side="left") - 1, 0, len(knot_times) - 2)
    t0, t1 = knot_times[segment], knot_times[segment + 1]
    span = (t1 - t0)[:, None]
    s = ((t - t0)[:, None]) / span
    p0, p1 = knots[segment], knots[segment + 1]
    v0, v1 = slopes[segment] * span, slopes[segment + 1] * span
    if curvature is None:
        position, velocity, acceleration = _cubic(s, p0, p1, v0, v1)
    else:
        a0, a1 = curvature[segment] * span**2, curvature[segment + 1] * span**2
        position, velocity, acceleration = _quintic(s, p0, p1, v0, v1, a0, a1)
    velocity = velocity / span
    acceleration = acceleration / span**2
    position[-1], velocity[-1], acceleration[-1] = waypoints.positions[-1], 0.0, 0.0
    return SampledMotion(position, velocity, acceleration)


def _inner_slopes(times: FloatArray, knots: FloatArray, start_velocity: FloatArray) -> FloatArray:
    """Velocities at the knots when none are given: the start's own, the mean of the two
    neighbouring secants inside (0 where they differ in sign: no overshoot), rest at the end."""
    secants = np.diff(knots, axis=0) / np.diff(times)[:, None]
    slopes = np.zeros_like(knots)
    slopes[0] = start_velocity
    if len(knots) > 2:
        before, after = secants[:-1], secants[1:]
        slopes[1:-1] = np.where(before * after > 0.0, 0.5 * (before + after), 0.0)
    return slopes


def _cubic(
    s: FloatArray, p0: FloatArray, p1: FloatArray, v0: FloatArray, v1: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cubic Hermite on s in [0, 1] with end slopes v0, v1 (per unit s): value, d/ds, d2/ds2."""
    s2, s3 = s * s, s * s * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    d00, d10, d01, d11 = 6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s
    e00, e10, e01, e11 = 12 * s - 6, 6 * s - 4, -12 * s + 6, 6 * s - 2
    position = h00 * p0 + h10 * v0 + h01 * p1 + h11 * v1
    velocity = d00 * p0 + d10 * v0 + d01 * p1 + d11 * v1
    acceleration = e00 * p0 + e10 * v0 + e01 * p1 + e11 * v1
    return position, velocity, acceleration


def _quintic(
    s: FloatArray,
    p0: FloatArray,
    p1: FloatArray,
    v0: FloatArray,
    v1: FloatArray,
    a0: FloatArray,
    a1: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Quintic on s in [0, 1] matching value, slope and curvature at both ends."""
    c0, c1, c2 = p0, v0, 0.5 * a0
    c3 = 10 * (p1 - p0) - 6 * v0 - 4 * v1 - 1.5 * a0 + 0.5 * a1
    c4 = -15 * (p1 - p0) + 8 * v0 + 7 * v1 + 1.5 * a0 - a1
    c5 = 6 * (p1 - p0) - 3 * v0 - 3 * v1 - 0.5 * a0 + 0.5 * a1
    position = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    velocity = c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
    acceleration = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
    return position, velocity, acceleration


def _empty(values: Rows) -> bool:
    """No rows, or only empty ones (a ROS point leaves a field it does not give empty)."""
    return len(values) == 0 or all(len(row) == 0 for row in values)


def _matrix(arm: str, field: str, rows: Rows, points: int, columns: int) -> FloatArray:
    if len(rows) != points:
        raise TrajectoryRefused(arm, f"{len(rows)} rows of {field} for {points} points")
    for index, row in enumerate(rows):
        if len(row) != columns:
            raise TrajectoryRefused(
                arm, f"point {index} has {len(row)} {field}, expected {columns} (one per joint)"
            )
    try:
        values = np.array(rows, dtype=float).reshape(points, columns)
    except (TypeError, ValueError):
        raise TrajectoryRefused(arm, f"{field} must be numbers") from None
    if not np.all(np.isfinite(values)):
        index = int(np.argmax(~np.all(np.isfinite(values), axis=1)))
        raise TrajectoryRefused(arm, f"point {index}'s {field} are not all finite numbers")
    return values
