"""A straight tool line in joint space: dense IK along the line, jerk-limited timing.

Community Ruckig has no waypoints, so a linear move is built in three passes:

1. geometry: the frame's pose ``T(s)``, ``s`` in [0, 1], goes in a straight line
   from its start position to the goal while its orientation turns about one
   axis (slerp). IK is solved at knots at most 2 mm / 10 mrad apart, each seeded
   by the previous one (no random restarts: they would jump to another
   branch), and joined by a cubic Hermite spline ``q(s)``. The spline between
   knots is checked against the line; the knots are doubled until it is within
   0.2 mm / 1 mrad (a joint jump, e.g. at a singularity, never converges and is
   refused);
2. timing: Ruckig plans ``s(t)`` from rest to rest with limits derived from the
   largest ``|dq/ds|`` and ``|d2q/ds2|`` so that ``dq/dt = q' s'`` and
   ``d2q/dt2 = q'' s'^2 + q' s''`` stay within the joints' limits;
3. check: the sampled joint velocities and accelerations are compared with the
   limits and the timing is slowed down (``s'`` by k, ``s''`` by k^2,
   ``s'''`` by k^3) until they fit.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pinocchio as pin
import ruckig

from armfleet.controllers.jerk_limited_trajectory import SampledMotion, TrajectoryError, calculate
from armfleet.controllers.position_controller import PositionController
from armfleet.errors import UnreachablePose
from armfleet.kinematics.inverse_kinematics import InverseKinematics
from armfleet.messages import FloatArray

KNOT_SPACING_M = 2e-3
KNOT_SPACING_RAD = 1e-2
LINE_TOLERANCE_M = 2e-4
LINE_TOLERANCE_RAD = 1e-3
_MIN_SEGMENTS = 8
_REFINEMENTS = 4

_Line = Callable[[float], pin.SE3]


class LinearPathPlanner:
    """Plans straight-line motions of one frame of one arm.

    Args:
        arm: arm name (for errors).
        ik: the arm's IK solver.
        controller: the arm's (configured) position controller: its joints'
            limits and its control period, at which the motion is sampled.
    """

    def __init__(self, arm: str, ik: InverseKinematics, controller: PositionController) -> None:
        self._arm_name = arm
        self._ik = ik
        self._arm = controller.arm.kinematics.arm_indices
        self._lower, self._upper = controller.lower, controller.upper
        self._velocity = controller.max_velocity
        dofs = self._lower.size
        self._acceleration = np.full(dofs, controller.parameters["max_acceleration_rad_s2"])
        self._jerk = np.full(dofs, controller.parameters["max_jerk_rad_s3"])
        self._period = controller.period

    def plan(self, frame: str, link: str, start: FloatArray, goal: pin.SE3) -> SampledMotion:
        """Samples (one per period) moving ``frame`` in a straight line to ``goal``.

        Args:
            frame: the moving frame (prefixed name); ``link`` names it in errors.
            start: every movable joint at the start, at rest [rad or m].
            goal: world pose of the frame at the end.

        Raises:
            UnreachablePose: a point of the line has no IK solution near the previous one.
        """
        origin = self._ik.frame_pose(frame, start)
        translation = goal.translation - origin.translation
        rotation = pin.log3(origin.rotation.T @ goal.rotation)
        if np.abs(translation).max() < 1e-12 and np.abs(rotation).max() < 1e-12:
            here = start[self._arm][None, :]
            return SampledMotion(here.copy(), np.zeros_like(here), np.zeros_like(here))
        segments = max(
            _MIN_SEGMENTS,
            math.ceil(float(np.linalg.norm(translation)) / KNOT_SPACING_M),
            math.ceil(float(np.linalg.norm(rotation)) / KNOT_SPACING_RAD),
        )

        def on_line(s: float) -> pin.SE3:
            return pin.SE3(
                origin.rotation @ pin.exp3(s * rotation), origin.translation + s * translation
            )

        for _ in range(_REFINEMENTS):
            knots = self._knots(frame, link, start, on_line, segments)
            slopes = np.gradient(knots, 1.0 / segments, axis=0, edge_order=2)
            deviation = self._deviation(frame, start, on_line, knots, slopes)
            if deviation[0] <= LINE_TOLERANCE_M and deviation[1] <= LINE_TOLERANCE_RAD:
                return self._time(knots, slopes)
            segments *= 2
        raise UnreachablePose(
            self._arm_name, link, *deviation, where=" along a straight line (a singularity?)"
        )

    def _knots(
        self, frame: str, link: str, start: FloatArray, on_line: _Line, segments: int
    ) -> FloatArray:
        knots = np.empty((segments + 1, self._arm.size))
        knots[0] = start[self._arm]
        q = np.array(start, dtype=float)
        for i in range(1, segments + 1):
            solution = self._ik.solve(frame, on_line(i / segments), q, restarts=False)
            if not solution.converged:
                where = f" at {i / segments:.0%} of the straight line"
                raise UnreachablePose(
                    self._arm_name,
                    link,
                    solution.position_error_m,
                    solution.rotation_error_rad,
                    where,
                )
            q = solution.positions
            knots[i] = q[self._arm]
        return knots

    def _deviation(
        self, frame: str, start: FloatArray, on_line: _Line, knots: FloatArray, slopes: FloatArray
    ) -> tuple[float, float]:
        """Largest distance and angle of the spline's midpoints from the line."""
        segments = len(knots) - 1
        middles = (np.arange(segments) + 0.5) / segments
        q = np.array(start, dtype=float)
        worst_m = worst_rad = 0.0
        for s, row in zip(middles, hermite(knots, slopes, middles)[0], strict=True):
            q[self._arm] = row
            error = self._ik.frame_pose(frame, q).actInv(on_line(float(s)))
            worst_m = max(worst_m, float(np.linalg.norm(error.translation)))
            worst_rad = max(worst_rad, float(np.linalg.norm(pin.log3(error.rotation))))
        return worst_m, worst_rad

    def _time(self, knots: FloatArray, slopes: FloatArray) -> SampledMotion:
        segments = len(knots) - 1
        curvature = np.gradient(slopes, 1.0 / segments, axis=0, edge_order=2)
        with np.errstate(divide="ignore"):
            per_slope = np.abs(slopes).max(axis=0)
            per_curvature = np.abs(curvature).max(axis=0)
            speed = min(
                float(np.min(self._velocity / per_slope)),
                float(np.min(np.sqrt(0.5 * self._acceleration / per_curvature))),
            )
            acceleration = float(np.min(0.5 * self._acceleration / per_slope))
            jerk = float(np.min(self._jerk / (3.0 * per_slope)))
        limits = np.array([speed, acceleration, jerk])
        if not np.all(np.isfinite(limits)):  # nothing to move: any finite timing will do
            limits = np.nan_to_num(limits, posinf=1.0)
        for _ in range(8):
            motion, ratio_v, ratio_a = self._sample(knots, slopes, limits)
            if ratio_v <= 1.0 and ratio_a <= 1.0:
                return motion
            k = 1.02 * max(ratio_v, math.sqrt(ratio_a), 1.0)
            limits /= [k, k * k, k**3]
        raise TrajectoryError("cannot time the straight line within the joint limits")

    def _sample(
        self, knots: FloatArray, slopes: FloatArray, limits: FloatArray
    ) -> tuple[SampledMotion, float, float]:
        otg = ruckig.Ruckig(1, self._period)
        path = ruckig.InputParameter(1)
        path.current_position, path.target_position = [0.0], [1.0]
        path.max_velocity = [float(limits[0])]
        path.max_acceleration = [float(limits[1])]
        path.max_jerk = [float(limits[2])]
        timing = ruckig.Trajectory(1)
        result = calculate(otg, path, timing)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            raise TrajectoryError(f"Ruckig cannot time the straight line: {result}")
        steps = max(1, math.ceil(timing.duration / self._period - 1e-9))
        times = np.minimum(np.arange(1, steps + 1) * self._period, timing.duration)
        s, s_dot, s_ddot = np.array([[x[0] for x in timing.at_time(t)] for t in times]).T
        s = np.clip(s, 0.0, 1.0)
        position, first, second = hermite(knots, slopes, s)
        velocity = first * s_dot[:, None]
        acceleration = second * (s_dot**2)[:, None] + first * s_ddot[:, None]
        position[-1], velocity[-1], acceleration[-1] = knots[-1], 0.0, 0.0
        np.clip(position, self._lower, self._upper, out=position)
        ratio_v = float(np.max(np.abs(velocity) / self._velocity))
        ratio_a = float(np.max(np.abs(acceleration) / self._acceleration))
        return SampledMotion(position, velocity, acceleration), ratio_v, ratio_a


def hermite(
    knots: FloatArray, slopes: FloatArray, s: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cubic Hermite spline through ``knots`` (uniform in [0, 1]) and its first two
    derivatives in ``s``, at the parameters ``s``."""
    segments = len(knots) - 1
    scaled = np.asarray(s) * segments
    index = np.minimum(np.floor(scaled).astype(int), segments - 1)
    u = (scaled - index)[:, None]
    h = 1.0 / segments
    p0, p1 = knots[index], knots[index + 1]
    m0, m1 = slopes[index] * h, slopes[index + 1] * h
    u2, u3 = u * u, u * u * u
    value = (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0 + (3 * u2 - 2 * u3) * p1
    value += (u3 - u2) * m1
    first = (6 * u2 - 6 * u) * (p0 - p1) + (3 * u2 - 4 * u + 1) * m0 + (3 * u2 - 2 * u) * m1
    second = (12 * u - 6) * (p0 - p1) + (6 * u - 4) * m0 + (6 * u - 2) * m1
    return value, first / h, second / (h * h)
