"""OMPL's RRT-Connect and path simplifier over a :class:`PlanningProblem`.

OMPL 2.x (nanobind bindings) calls the collision check back in Python once per state,
and with the compiled check once per motion (:class:`_CompiledMotions`): the Python
callback per state cost about as much as the compiled check it called (~7 µs). Motions
are checked every ``resolution`` of the state space's extent, the states on them against
the clearance; :func:`armfleet.planning.path_check` then proves the result.

OMPL objects are made per search and dropped after it: a validity callback that
outlived the interpreter would be reported as a leak by nanobind at exit.

A search runs within a time (a deadline) or within a number of RRT-Connect iterations
(a budget: ``PlannerTerminationCondition`` of a callable that counts its calls, one per
iteration). A budgeted search is reproducible: it restarts OMPL's random numbers from a
seed made of the problem's start and goal (and the attempt), so the same request gives
the same path, bit for bit, whatever ran before it in the process, on a busy machine or
an idle one. Nothing else in it depends on time: the simplifier's steps are bounded by
the path's vertices (``reduceVertices`` tries as many pairs as the path has states,
``ropeShortcutPath`` walks it once), not by a clock. Each OMPL object takes its random
numbers from one generator per process at its creation, so searches run one at a time
(:data:`_ONE_SEARCH_AT_A_TIME`): a search in another thread would draw seeds in between.
"""

from __future__ import annotations

import math
import threading
import time
import zlib
from dataclasses import dataclass
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from armfleet.messages import FloatArray
from armfleet.planning.problem import PlanningProblem

# OMPL reports each search on the console; a failed search is reported by PlanningFailed.
ou.setLogLevel(ou.LOG_ERROR)
#: Seed of OMPL's random numbers, set once per process before any search: the same
#: requests in the same order give the same plans, run after run.
OMPL_SEED = 16
ou.RNG.setSeed(OMPL_SEED)


def restart_random_numbers(seed: int) -> None:
    """Restart OMPL's random numbers from ``seed``, so that the searches that follow do
    not depend on the searches made before them in this process (a sweep's run, which
    must give the same plans whichever runs its worker made before).

    Every search makes its own OMPL objects, and each object takes its seed from OMPL's
    seed generator, which this restarts.
    """
    ou.setLogLevel(ou.LOG_NONE)  # OMPL says generation has already started: that is meant
    try:
        ou.RNG.setSeed(1 + seed % (2**32 - 1))  # OMPL ignores a seed of 0
    finally:
        ou.setLogLevel(ou.LOG_ERROR)


#: OMPL's seed generator is one per process and every OMPL object draws its seed from it
#: when made: searches take turns, so that a budgeted search's objects get the seeds its
#: restart gave them.
_ONE_SEARCH_AT_A_TIME = threading.Lock()


def search_seed(problem: PlanningProblem, attempt: int) -> int:
    """The seed of a budgeted search: the same for the same start, goal and attempt, in
    any process on any machine (CRC-32 of their bytes, little-endian doubles)."""
    data = b"".join(
        np.ascontiguousarray(q, dtype="<f8").tobytes() for q in (problem.start, problem.goal)
    )
    return zlib.crc32(data + attempt.to_bytes(4, "little"))


#: Motion-check step as a fraction of the state space's extent (OMPL's resolution).
MOTION_RESOLUTION = 0.01
#: OMPL's ``PathSimplifier`` steps run on a solution, in order. Vertices are reduced again
#: after the rope shortcuts: half the waypoints of two-arm paths (a median of 10.5 to 4.5),
#: motions 15 % shorter, and fewer corners for the smooth timing to prove.
SIMPLIFICATION = ("reduceVertices", "ropeShortcutPath", "reduceVertices")


@dataclass
class SearchResult:
    """What one search produced.

    Attributes:
        path: waypoints (rows) from start to goal, or None when no path was found.
        samples: states in the planner's trees when it stopped.
        search_s, simplify_s: wall time of the search and of the simplification [s].
        iterations: RRT-Connect iterations the search ran.
    """

    path: FloatArray | None
    samples: int
    search_s: float
    simplify_s: float = 0.0
    iterations: int = 0


class OmplRrtConnect:
    """Bidirectional RRT (RRT-Connect) then OMPL's vertex reduction and rope shortcuts,
    within a deadline or a number of iterations."""

    name = "OMPL RRTConnect"

    def __init__(
        self,
        resolution: float = MOTION_RESOLUTION,
        simplification: tuple[str, ...] = SIMPLIFICATION,
    ) -> None:
        self.resolution = resolution
        self.simplification = simplification

    def search(
        self,
        problem: PlanningProblem,
        deadline: float | None = None,
        iterations: int | None = None,
        attempt: int = 0,
    ) -> SearchResult:
        """Search a path from ``problem.start`` to ``problem.goal``. Start and goal must
        be valid.

        Args:
            problem: what to plan.
            deadline: stop searching at this ``time.perf_counter()`` time (with no
                ``iterations``).
            iterations: stop after this many RRT-Connect iterations instead, and restart
                OMPL's random numbers from :func:`search_seed`: the result is then the
                same in any process, under any load.
            attempt: which search of the request this is (its seed with ``iterations``).

        Raises:
            ValueError: neither ``deadline`` nor ``iterations`` given.
        """
        if deadline is None and iterations is None:
            raise ValueError("a search needs a deadline or a number of iterations")
        with _ONE_SEARCH_AT_A_TIME:
            if iterations is not None:
                restart_random_numbers(search_seed(problem, attempt))
            return self._search(problem, deadline, iterations)

    def _search(
        self, problem: PlanningProblem, deadline: float | None, iterations: int | None
    ) -> SearchResult:
        n = problem.dimension
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):
            bounds.setLow(i, float(problem.lower[i]))
            bounds.setHigh(i, float(problem.upper[i]))
        space.setBounds(bounds)
        info = ob.SpaceInformation(space)
        valid = problem.checker.valid
        info.setStateValidityChecker(lambda state: valid(np.asarray(state[0:n])))
        info.setStateValidityCheckingResolution(self.resolution)
        compiled = problem.checker.compiled
        if compiled is not None:  # kept alive by this frame for the search's length
            validator = _CompiledMotions(
                info, compiled, n, self.resolution * space.getMaximumExtent()
            )
            info.setMotionValidator(validator)
        info.setup()
        start, goal = info.allocState(), info.allocState()
        start[0:n] = problem.start.tolist()
        goal[0:n] = problem.goal.tolist()
        definition = ob.ProblemDefinition(info)
        definition.setStartAndGoalStates(start, goal)
        planner = og.RRTConnect(info)
        planner.setProblemDefinition(definition)
        planner.setup()
        counter = _IterationCounter(iterations)
        began = time.perf_counter()
        if iterations is None:
            assert deadline is not None  # search() checked it
            planner.solve(max(1e-3, deadline - began))
        else:
            planner.solve(ob.PlannerTerminationCondition(counter.spent))
        search_s = time.perf_counter() - began
        data = ob.PlannerData(info)
        planner.getPlannerData(data)
        samples = int(data.numVertices())
        if not definition.hasExactSolution():
            return SearchResult(None, samples, search_s, iterations=counter.used)
        path = definition.getSolutionPath()
        began = time.perf_counter()
        simplifier = og.PathSimplifier(info)
        for step in self.simplification:
            getattr(simplifier, step)(path)
        simplify_s = time.perf_counter() - began
        states = path.getStates()
        waypoints = np.array([state[0:n] for state in states], dtype=float)
        waypoints[0], waypoints[-1] = problem.start, problem.goal
        return SearchResult(waypoints, samples, search_s, simplify_s, counter.used)


class _CompiledMotions(ob.MotionValidator):  # type: ignore[misc] # OMPL has no stubs
    """OMPL's discrete motion check (the end, then the states a ``segment`` apart between,
    middle ones first) in one compiled call per motion instead of one Python callback per
    state."""

    def __init__(
        self, info: ob.SpaceInformation, compiled: Any, dimension: int, segment: float
    ) -> None:
        super().__init__(info)
        self._compiled = compiled
        self._dimension = dimension
        self._segment = segment

    def checkMotion(self, first: ob.State, second: ob.State) -> bool:  # noqa: N802 - OMPL's
        n = self._dimension
        start = np.array(first[0:n], dtype=float)
        end = np.array(second[0:n], dtype=float)
        segments = max(1, math.ceil(float(np.linalg.norm(end - start)) / self._segment))
        return bool(self._compiled.clear_motion(start, end, segments))


class _IterationCounter:
    """OMPL's termination condition as a count: RRT-Connect asks it once per iteration."""

    def __init__(self, limit: int | None) -> None:
        self.limit = limit
        self.used = 0

    def spent(self) -> bool:
        """Whether the limit is reached (then no iteration is counted)."""
        if self.limit is not None and self.used >= self.limit:
            return True
        self.used += 1
        return False
