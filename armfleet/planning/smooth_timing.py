"""Time a joint path through its waypoints without stopping, and prove what is executed.

Each waypoint gets a *pass-through velocity*: per joint, zero where the joint turns back
there, else the slower of its mean speeds on the two segments it joins (each timed rest
to rest, :class:`~armfleet.planning.path_timing.StraightSegment`) times
:data:`PASS_THROUGH_GAIN`, within its velocity limit. From waypoint to waypoint Ruckig
then times all joints together (time-synchronised, jerk-limited, time-optimal for the
given ends), from the pass-through state at one waypoint (acceleration zero) to the one
at the next: the motion reaches every waypoint exactly, every joint within its
velocity, acceleration and jerk limits, and the arms of a joint plan start on the same
step and arrive at the same instant.

Between waypoints such a segment bends away from the straight line the search proved
clear. So each one is proven again as it is executed
(:class:`~armfleet.planning.curve_check.CurveCertifier`), and it must stay inside the
box of its two waypoints (no joint overshoots them, so no joint leaves its range). A
segment that fails either halves the pass-through velocities at its ends and is timed
again; after :data:`HALVINGS` halvings its ends stop (velocity zero), and a segment
with both ends stopped is the straight, proven one timed rest to rest. So the worst
case is the reference timing, and whatever is returned is proven contact-free as it is
executed.
"""

from __future__ import annotations

import itertools

import numpy as np
import ruckig

from armfleet.controllers.jerk_limited_trajectory import calculate
from armfleet.messages import FloatArray
from armfleet.planning.curve_check import CurveCertifier
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.path_timing import (
    JointLimits,
    Kinematics,
    Segment,
    StraightSegment,
    TimedSegments,
)
from armfleet.planning.scene import CollisionChecker

#: Pass-through speed of a joint against the slower of its mean speeds on the two
#: segments it joins (each timed rest to rest).
PASS_THROUGH_GAIN = 2.0
#: Halvings of a waypoint's pass-through velocity before it becomes a stop.
HALVINGS = 3
#: How far a joint may pass beyond its waypoints along a segment [rad] (rounding).
OVERSHOOT_RAD = 1e-9
#: Knots this many times further apart than the worst case are tried first on each curved
#: segment (kept when the accelerations at them bound the deviation within its share).
KNOT_STRETCH = 2.0


class CurvedSegment:
    """All joints from one pass-through state to the next, timed together by Ruckig.

    Args:
        start, end: the waypoints.
        start_velocity, end_velocity: the joints' velocities there (accelerations zero).
        limits: the joints' limits.

    Raises:
        ValueError: Ruckig finds no motion between these states.
    """

    def __init__(
        self,
        start: FloatArray,
        end: FloatArray,
        start_velocity: FloatArray,
        end_velocity: FloatArray,
        limits: JointLimits,
    ) -> None:
        dofs = len(start)
        motion = ruckig.InputParameter(dofs)
        motion.current_position, motion.target_position = start.tolist(), end.tolist()
        motion.current_velocity = start_velocity.tolist()
        motion.target_velocity = end_velocity.tolist()
        motion.max_velocity = limits.velocity.tolist()
        motion.max_acceleration = limits.acceleration.tolist()
        motion.max_jerk = limits.jerk.tolist()
        self._trajectory = ruckig.Trajectory(dofs)
        try:
            result = calculate(ruckig.Ruckig(dofs), motion, self._trajectory)
        except ruckig.RuckigError as exc:
            raise ValueError(f"Ruckig cannot time the segment: {exc}") from exc
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            raise ValueError(f"Ruckig cannot time the segment: {result}")
        extrema = self._trajectory.position_extrema
        low = np.array([e.min for e in extrema])
        high = np.array([e.max for e in extrema])
        #: Whether every joint stays between its two waypoints.
        self.inside = bool(
            np.all(low >= np.minimum(start, end) - OVERSHOOT_RAD)
            and np.all(high <= np.maximum(start, end) + OVERSHOOT_RAD)
        )
        self._end = end

    @property
    def duration(self) -> float:
        return float(self._trajectory.duration)

    def at(self, times: FloatArray) -> Kinematics:
        trajectory = self._trajectory
        rows = [trajectory.at_time(float(t)) for t in times]
        position = np.array([r[0] for r in rows])
        velocity = np.array([r[1] for r in rows])
        acceleration = np.array([r[2] for r in rows])
        return position, velocity, acceleration


class SmoothPath(TimedSegments):
    """A polyline timed through its waypoints without stopping, proven as executed.

    Args:
        waypoints: states (rows), each segment proven clear, the first where the arms
            are now (at rest).
        limits: the joints' limits.
        checker: the request's collision checker (proves the curved segments).
    """

    def __init__(
        self, waypoints: FloatArray, limits: JointLimits, checker: CollisionChecker
    ) -> None:
        points = np.asarray(waypoints, dtype=float)
        self._limits = limits
        certifier = CurveCertifier(checker, limits.acceleration, limits.jerk)
        straight = [StraightSegment(a, b, limits) for a, b in itertools.pairwise(points)]
        velocities = pass_through_velocities(points, straight, limits)
        halvings = np.zeros(len(points), dtype=int)
        segments: list[Segment | None] = [None] * len(straight)
        while True:
            failed = []
            for k, segment in enumerate(segments):
                if segment is None:
                    segments[k] = segment = _timed(k, points, velocities, straight, limits)
                    if segment is None or not _proven(segment, points[k], certifier):
                        failed.append(k)
            if not failed:
                break
            for k in failed:
                for end in (k, k + 1):
                    halvings[end] += 1
                    velocities[end] *= 0.5 if halvings[end] <= HALVINGS else 0.0
                for neighbour in (k - 1, k, k + 1):
                    if 0 <= neighbour < len(segments):
                        segments[neighbour] = None
        super().__init__(points, [s for s in segments if s is not None])
        #: The rest-to-rest timing of the same waypoints (the reference).
        self.rest_to_rest = TimedSegments(points, list(straight))

    def first_unclear(self, checker: CollisionChecker) -> FloatArray | None:
        """A state of the executed motion ``checker`` does not prove clear, or None."""
        certifier = CurveCertifier(checker, self._limits.acceleration, self._limits.jerk)
        straight = PathCertifier(checker)
        for k, segment in enumerate(self._segments):
            a, b = self.waypoints[k], self.waypoints[k + 1]
            if isinstance(segment, CurvedSegment):
                failure = _first_failure(segment, a, certifier)
                if failure is not None:
                    return failure
            else:
                found = straight.first_failure(np.array([a, b]))
                if found is not None:
                    return found[1]
        return None


def pass_through_velocities(
    points: FloatArray, straight: list[StraightSegment], limits: JointLimits
) -> FloatArray:
    """Per waypoint (rows), the joints' velocities to pass it with; rest at both ends."""
    velocities = np.zeros_like(points)
    deltas = np.diff(points, axis=0)
    mean = np.array([d / max(s.duration, 1e-12) for d, s in zip(deltas, straight, strict=True)])
    for k in range(1, len(points) - 1):
        incoming, outgoing = mean[k - 1], mean[k]
        same = np.sign(incoming) == np.sign(outgoing)
        speed = np.minimum(np.abs(incoming), np.abs(outgoing)) * PASS_THROUGH_GAIN
        velocities[k] = np.where(same, np.sign(incoming) * np.minimum(speed, limits.velocity), 0.0)
    return velocities


def _timed(
    k: int,
    points: FloatArray,
    velocities: FloatArray,
    straight: list[StraightSegment],
    limits: JointLimits,
) -> Segment | None:
    """Segment ``k`` between its pass-through states: straight when both ends stop, None
    when Ruckig finds no motion inside the waypoints' box."""
    start_velocity, end_velocity = velocities[k], velocities[k + 1]
    if not start_velocity.any() and not end_velocity.any():
        return straight[k]
    try:
        segment = CurvedSegment(points[k], points[k + 1], start_velocity, end_velocity, limits)
    except ValueError:
        return None
    return segment if segment.inside else None


def _proven(segment: Segment, start: FloatArray, certifier: CurveCertifier) -> bool:
    """Whether the segment, as executed, is proven contact-free (a straight one is)."""
    if not isinstance(segment, CurvedSegment):
        return True
    return _first_failure(segment, start, certifier) is None


def _first_failure(
    segment: CurvedSegment, start: FloatArray, certifier: CurveCertifier
) -> FloatArray | None:
    """The first state of ``segment`` (from ``start``) not proven clear, or None.

    Knots :attr:`~CurveCertifier.knot_period` apart keep the deviation within its share
    whatever the accelerations; where the segment accelerates less, knots
    :data:`KNOT_STRETCH` times as far apart may keep it too (bounded from the accelerations
    at the knots), and are taken then: fewer chords to walk."""
    for stretch in (KNOT_STRETCH, 1.0):
        count = max(1, int(np.ceil(segment.duration / (stretch * certifier.knot_period))))
        period = segment.duration / count
        times = np.linspace(0.0, segment.duration, count + 1)
        knots, _, accelerations = segment.at(times)
        if stretch == 1.0 or certifier.within_share(
            certifier.chord_deviations(period, accelerations)
        ):
            break
    knots[0] = start
    failure = certifier.first_failure(knots, period, accelerations)
    return None if failure is None else failure[1]
