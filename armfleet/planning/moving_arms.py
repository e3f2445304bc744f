"""Arms outside a request that are moving: their motion, and the check of a plan in time.

An arm outside the request stands in the scene where its motion will end; the planned
path is then timed and checked *in time* against every moving arm's remaining
reference, sampled along both motions and proven clear between samples as paths are
(:class:`~armfleet.planning.path_check.PathCertifier` over the joint state of the
planned and the moving arms together). If they would meet, the plan waits at its start
a little longer and is checked again, up to the moving arms' end.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armfleet.messages import FloatArray
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.path_timing import TimedSegments
from armfleet.planning.scene import CollisionChecker, PlanningScene

#: Time between the samples of the in-time check [s] (proven clear between them).
SAMPLE_PERIOD_S = 0.02
#: Start delays tried, as fractions of the moving arms' remaining time.
DELAY_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 1.0)


@dataclass(frozen=True)
class MovingArm:
    """An arm outside the request and its remaining motion.

    Attributes:
        name: arm name.
        positions: its controlled joints' reference (rows) at each coming period;
            the last row is where it stops.
        period: its controller's period [s].
    """

    name: str
    positions: FloatArray
    period: float

    @property
    def duration(self) -> float:
        return len(self.positions) * self.period

    @property
    def final(self) -> FloatArray:
        last: FloatArray = self.positions[-1]
        return last

    def at(self, times: FloatArray) -> FloatArray:
        """Its reference positions (rows) at ``times`` after now [s]; the last after its end."""
        index = np.clip(np.floor(times / self.period + 1e-9).astype(int) - 1, -1, None)
        index = np.minimum(index, len(self.positions) - 1)
        rows: FloatArray = self.positions[np.maximum(index, 0)].copy()
        before = index < 0
        if before.any():
            rows[before] = self.positions[0]  # within the first period: as good as now
        return rows


@dataclass(frozen=True)
class Conflict:
    """Where a timed plan would meet a moving arm: the arm and the time after the start [s]."""

    arm: str
    time_s: float


def conflict_in_time(
    checker: CollisionChecker,
    timed: TimedSegments,
    delay_s: float,
    movers: Sequence[MovingArm],
) -> Conflict | None:
    """The first meeting of the plan (started after ``delay_s``) with a moving arm, or None.

    ``checker`` checks the planned arms and the moving arms together, in that order."""
    if not movers:
        return None
    scene = checker.scene
    horizon = max(delay_s + timed.duration, max(m.duration for m in movers))
    times = np.append(np.arange(0.0, horizon, SAMPLE_PERIOD_S), horizon)
    own = timed.at(times - delay_s)[0]
    states = np.hstack([own, *(m.at(times) for m in movers)])
    failure = PathCertifier(checker).first_failure(states)
    if failure is None:
        return None
    index, state = failure
    found = checker.collision(state)
    owners = {scene.owner_of(link) for link in found[:2]} if found else set()
    blocking = next((m.name for m in movers if m.name in owners), movers[0].name)
    return Conflict(blocking, float(times[index]))


def find_start_delay(
    scene: PlanningScene,
    planned: Sequence[str],
    timed: TimedSegments,
    movers: Sequence[MovingArm],
) -> tuple[float, Conflict | None]:
    """The shortest tried start delay [s] with no conflict, and the conflict when none works
    (then the delay returned is meaningless)."""
    if not movers:
        return 0.0, None
    longest = max(m.duration for m in movers)
    checker = scene.checker([*planned, *(m.name for m in movers)])
    conflict = None
    for fraction in DELAY_FRACTIONS:
        delay = fraction * longest
        conflict = conflict_in_time(checker, timed, delay, movers)
        if conflict is None:
            return delay, None
    return 0.0, conflict
