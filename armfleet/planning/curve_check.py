"""The proof of clearance for a motion that leaves the polyline: a curve in joint space.

A smooth motion through waypoints (:mod:`~armfleet.planning.smooth_timing`) bends away
from the straight segments the search proved clear, so the curve it follows is proven
again, as executed. It is cut at *knots* ``h`` seconds apart. Between two knots ``a``
and ``b`` each joint stays within ``δ_i = A_i h² / 8`` of the chord from ``a`` to ``b``
(the error bound of linear interpolation for a joint whose acceleration is at most
``A_i``). The chord is walked as
:class:`~armfleet.planning.path_check.PathCertifier` walks a segment, with checked
states a step ``Δq`` apart; a point of the curve is then within ``|Δq| / 2 + δ`` of a
checked state, joint by joint, and the reach bounds ``r_i`` turn that into at most
``Σ_i r_i (|Δq_i| / 2 + δ_i)`` in the workspace. Steps are sized so that this stays
within the margin the checked states keep (summed over the arms between bodies, per arm
within one), as the certifier's are: every point of the executed curve, and so every
sample the controllers follow, is proven contact-free. ``h`` is chosen so that the
deviation takes at most :data:`DEVIATION_SHARE` of the smallest margin.

The compiled check walks the chords adaptively instead (steps sized by the distances it
finds), each pair's slack less what the deviation can take of it, and refuses a curve where
the deviation would leave a pair less than half its clearance at a checked state (the steps
would shrink toward nothing there).
"""

from __future__ import annotations

import math

import numpy as np

from armfleet.messages import FloatArray
from armfleet.planning.path_check import joint_levers, walk
from armfleet.planning.scene import CollisionChecker

#: Share of the smallest margin the deviation from the chords may take: fewer knots for a
#: larger share, less slack left per checked state (measured: 0.4 a little cheaper than
#: 0.25 in benchmarks/planning.py; above 0.5 the compiled walk would refuse every curve near
#: anything).
DEVIATION_SHARE = 0.4


class CurveCertifier:
    """Proves curves of one checker's joints contact-free, knot by knot.

    Args:
        checker: the request's collision checker (its scene's margins must be > 0).
        max_acceleration: per joint of a state, a bound on |q''| along the curves
            [rad/s^2].
        max_jerk: per joint, a bound on the curves' jerk [rad/s^3], if they keep one:
            then a chord's deviation is bounded from the accelerations at its two knots
            (:meth:`chord_deviations`), not from ``max_acceleration`` alone.
    """

    def __init__(
        self,
        checker: CollisionChecker,
        max_acceleration: FloatArray,
        max_jerk: FloatArray | None = None,
    ) -> None:
        scene = checker.scene
        if not (scene.clearance_m > 0.0 and scene.self_clearance_m > 0.0):
            raise ValueError("a contact-free proof needs margins > 0")
        self._checker = checker
        self._levers = joint_levers(checker)
        self._acceleration = np.asarray(max_acceleration, dtype=float)
        self._jerk = None if max_jerk is None else np.asarray(max_jerk, dtype=float)
        self._near = (scene.clearance_m, scene.self_clearance_m)
        self._far = (scene.far_clearance_m, scene.far_self_clearance_m)
        sizes = [scene.columns(arm).size for arm in checker.arms]
        self._bounds = np.cumsum([0, *sizes])[:-1]
        smallest = min(self._near)
        spread = float(self._levers @ self._acceleration)
        #: Time between knots [s]: the deviation from the chords is at most
        #: ``DEVIATION_SHARE`` of the smallest margin (all arms together).
        self.knot_period = math.sqrt(8.0 * DEVIATION_SHARE * smallest / max(spread, 1e-12))
        self._allowed = DEVIATION_SHARE * smallest

    def within_share(self, deviations: FloatArray) -> bool:
        """Whether chords of ``deviations`` (rows, :meth:`chord_deviations`) keep the
        deviation within :data:`DEVIATION_SHARE` of the smallest margin, as knots
        :attr:`knot_period` apart always do."""
        reach = np.asarray(deviations, dtype=float) @ self._levers
        return bool(np.all(reach <= self._allowed))

    def deviation(self, period: float) -> FloatArray:
        """Per joint: how far the curve can be from the chord of ``period`` seconds [rad]."""
        bound: FloatArray = self._acceleration * period**2 / 8.0
        return bound

    def chord_deviations(self, period: float, accelerations: FloatArray | None) -> FloatArray:
        """Per chord (rows) and joint: how far the curve can be from the chord between two
        knots ``period`` seconds apart [rad].

        With the knots' ``accelerations`` (rows) and a jerk bound ``J``, the acceleration
        between two knots is at most ``(|a_k| + |a_k+1| + J period) / 2`` (it changes by at
        most ``J`` per second from either end), and never more than ``max_acceleration``;
        without them, ``max_acceleration`` throughout (one row for every chord)."""
        if accelerations is None or self._jerk is None:
            return self.deviation(period)[None, :]
        ends = np.abs(np.asarray(accelerations, dtype=float))
        between = (ends[:-1] + ends[1:] + self._jerk * period) / 2.0
        bound: FloatArray = np.minimum(between, self._acceleration) * period**2 / 8.0
        return bound

    def steps(self, start: FloatArray, end: FloatArray, deviation: FloatArray, far: bool) -> int:
        """Equal steps along the chord from ``start`` to ``end`` that prove the curve within
        ``deviation`` of it, with the near (or far) margins (at least 1)."""
        between, within = self._far if far else self._near
        moved = np.add.reduceat(self._levers * np.abs(end - start), self._bounds)
        off = np.add.reduceat(self._levers * deviation, self._bounds)
        room_between = 2.0 * (between - float(off.sum()))
        room_within = 2.0 * (within - off)
        if room_between <= 0.0 or np.any(room_within <= 0.0):
            raise ValueError("knots too far apart: the deviation alone exceeds the margin")
        needed = max(float(moved.sum()) / room_between, float(np.max(moved / room_within)))
        return max(1, math.ceil(needed))

    def first_failure(
        self, knots: FloatArray, period: float, accelerations: FloatArray | None = None
    ) -> tuple[int, FloatArray] | None:
        """The first knot interval (``knots[k]`` to ``knots[k + 1]``, at most ``period``
        seconds apart along the curve) not proven clear, and the state that failed, or None.
        ``accelerations``: the curve's at the knots (rows), which bound each chord's
        deviation more tightly (:meth:`chord_deviations`).

        Each knot is checked (far, else against the clearance); each chord is walked in
        the far margins' steps, and again in the clearance's steps where an end is not
        far. The compiled check walks all chords in one call, in steps sized by the
        distances it finds, each pair's slack less what the deviation can take of it.
        """
        checker = self._checker
        deviations = self.chord_deviations(period, accelerations)
        if checker.compiled is not None:
            found = checker.compiled.first_failure(
                np.ascontiguousarray(knots, dtype=float), True, np.ascontiguousarray(deviations)
            )
            return None if found is None else (int(found[0]), np.asarray(found[1]))
        last = len(deviations) - 1
        return walk(
            checker,
            knots,
            lambda index, a, b, far: self.steps(a, b, deviations[min(index, last)], far),
        )
