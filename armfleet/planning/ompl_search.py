"""OMPL's RRT-Connect and path simplifier over a :class:`PlanningProblem`.

OMPL 2.x (nanobind bindings) calls the collision check back in Python once per
state: about 1.5 µs of a 20-60 µs broadphase check, so the callback is not the
cost. Motions are checked every ``resolution`` of the state space's extent, the
states on them against the clearance; :func:`armfleet.planning.path_check` then
checks the result again, finer.

OMPL objects are made per search and dropped after it: a validity callback that
outlived the interpreter would be reported as a leak by nanobind at exit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

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


#: Motion-check step as a fraction of the state space's extent (OMPL's resolution).
MOTION_RESOLUTION = 0.01
#: OMPL's ``PathSimplifier`` steps run on a solution, in order.
SIMPLIFICATION = ("reduceVertices", "ropeShortcutPath")


@dataclass
class SearchResult:
    """What one search produced.

    Attributes:
        path: waypoints (rows) from start to goal, or None when no path was found.
        samples: states in the planner's trees when it stopped.
        search_s, simplify_s: wall time of the search and of the simplification [s].
    """

    path: FloatArray | None
    samples: int
    search_s: float
    simplify_s: float = 0.0


class OmplRrtConnect:
    """Bidirectional RRT (RRT-Connect) then OMPL's shortcutting, vertex reduction and
    vertex collapsing, within the problem's time budget."""

    name = "OMPL RRTConnect"

    def __init__(
        self,
        resolution: float = MOTION_RESOLUTION,
        simplification: tuple[str, ...] = SIMPLIFICATION,
    ) -> None:
        self.resolution = resolution
        self.simplification = simplification

    def search(self, problem: PlanningProblem, deadline: float) -> SearchResult:
        """Search a path from ``problem.start`` to ``problem.goal`` until ``deadline``
        (``time.perf_counter()`` time). Start and goal must be valid."""
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
        info.setup()
        start, goal = info.allocState(), info.allocState()
        start[0:n] = problem.start.tolist()
        goal[0:n] = problem.goal.tolist()
        definition = ob.ProblemDefinition(info)
        definition.setStartAndGoalStates(start, goal)
        planner = og.RRTConnect(info)
        planner.setProblemDefinition(definition)
        planner.setup()
        began = time.perf_counter()
        planner.solve(max(1e-3, deadline - began))
        search_s = time.perf_counter() - began
        data = ob.PlannerData(info)
        planner.getPlannerData(data)
        samples = int(data.numVertices())
        if not definition.hasExactSolution():
            return SearchResult(None, samples, search_s)
        path = definition.getSolutionPath()
        began = time.perf_counter()
        simplifier = og.PathSimplifier(info)
        for step in self.simplification:
            getattr(simplifier, step)(path)
        simplify_s = time.perf_counter() - began
        states = path.getStates()
        waypoints = np.array([state[0:n] for state in states], dtype=float)
        waypoints[0], waypoints[-1] = problem.start, problem.goal
        return SearchResult(waypoints, samples, search_s, simplify_s)
