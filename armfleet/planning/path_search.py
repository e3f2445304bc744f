"""From a :class:`PlanningProblem` to a proven-clear joint path, or a :class:`PlanningFailed`.

1. The start and the goal must keep the clearance (else the pair is named).
2. The straight line is tried first: if the states the search would check on it are
   clear and it is proven clear, it is the path.
3. Otherwise the search (OMPL's RRT-Connect, then its simplifier) runs within the
   time budget, and its path must pass :class:`PathCertifier`; a path that fails is
   searched again, with motions checked finer, while time remains.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from armfleet.messages import FloatArray
from armfleet.planning.failure import FailureReason, PlanningFailed
from armfleet.planning.ompl_search import OmplRrtConnect
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.problem import PlanningProblem


@dataclass
class JointPath:
    """A path proven clear, and what finding it cost.

    Attributes:
        waypoints: states (rows) from start to goal; straight lines between them.
        samples: states the search sampled (0 when the straight line was clear).
        checks: collision checks made (search, simplification and proof).
        seconds: wall time per phase [s]: ``check`` (start and goal), ``search``,
            ``simplify``, ``certify``.
    """

    waypoints: FloatArray
    samples: int = 0
    checks: int = 0
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def length(self) -> float:
        """Joint-space length [rad]."""
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)))


def find_path(
    problem: PlanningProblem,
    search: OmplRrtConnect | None = None,
    deadline: float | None = None,
) -> JointPath:
    """A proven-clear path for ``problem``, by ``deadline`` (``time.perf_counter()`` time;
    ``problem.timeout_s`` from now by default: a request that spent some of its budget
    before, on IK and the scene, passes its own), or within ``problem.budget`` iterations
    of the search, over all its attempts (then the clock is not read to stop).

    Raises:
        PlanningFailed: the start or the goal is closer than the clearance to
            something (the pair is named), or no proven-clear path was found in
            ``problem.timeout_s`` (or ``problem.budget``).
    """
    search = search or OmplRrtConnect()
    checker = problem.checker
    began = time.perf_counter()
    if deadline is None:
        deadline = began + problem.timeout_s
    checks_before = checker.checks
    for state, reason in (
        (problem.start, FailureReason.START_IN_COLLISION),
        (problem.goal, FailureReason.GOAL_IN_COLLISION),
    ):
        if not checker.valid(state):
            raise _in_collision(problem, state, reason)
    seconds = {"check": time.perf_counter() - began}
    certifier = PathCertifier(checker)
    straight = np.array([problem.start, problem.goal])
    began = time.perf_counter()
    if _may_be_clear(problem, search) and certifier.first_failure(straight) is None:
        seconds["certify"] = time.perf_counter() - began
        return JointPath(straight, 0, checker.checks - checks_before, seconds)
    seconds["certify"] = time.perf_counter() - began
    seconds["search"] = seconds["simplify"] = 0.0
    samples, resolution, iterations, attempt = 0, search.resolution, 0, 0
    budget = problem.budget
    while time.perf_counter() < deadline if budget is None else iterations < budget:
        result = OmplRrtConnect(resolution, search.simplification).search(
            problem,
            deadline if budget is None else None,
            None if budget is None else budget - iterations,
            attempt,
        )
        iterations, attempt = iterations + max(1, result.iterations), attempt + 1
        samples += result.samples
        seconds["search"] += result.search_s
        seconds["simplify"] += result.simplify_s
        if result.path is None:
            break
        began = time.perf_counter()
        failure = certifier.first_failure(result.path)
        seconds["certify"] += time.perf_counter() - began
        if failure is None:
            return JointPath(result.path, samples, checker.checks - checks_before, seconds)
        resolution /= 4.0  # its motions touched between checked states: check them finer
    within, more = (
        (f"{problem.timeout_s:g} s", "more time (timeout_s; --planning-timeout)")
        if budget is None
        else (f"a budget of {budget} iterations", "a larger budget (budget; --budget)")
    )
    raise PlanningFailed(
        FailureReason.NO_PATH,
        f"no clear path within {within} ({samples} samples tried); "
        f"give {more}, less clearance, or another goal",
        arms=problem.arms,
        samples=samples,
        problem=problem,
    )


def _may_be_clear(problem: PlanningProblem, search: OmplRrtConnect) -> bool:
    """Whether the straight line from start to goal is worth proving: the states the
    search's motion check would try on it, middle ones first, are clear (a line through
    something usually fails at one of its first few, where the proof would walk up to it).
    Without the compiled check, always (the proof is then the only walk)."""
    compiled = problem.checker.compiled
    if compiled is None:
        return True
    extent = float(np.linalg.norm(problem.upper - problem.lower))
    segment = search.resolution * extent
    length = float(np.linalg.norm(problem.goal - problem.start))
    return bool(
        compiled.clear_motion(problem.start, problem.goal, max(1, math.ceil(length / segment)))
    )


def _in_collision(
    problem: PlanningProblem, state: FloatArray, reason: FailureReason
) -> PlanningFailed:
    found = problem.checker.collision(state)
    if found is None:  # the broadphase and the pair-by-pair check disagree: say so plainly
        return PlanningFailed(reason, "a pair is closer than its margin", arms=problem.arms)
    first, second, distance, margin = found
    where = "touches" if distance <= 0.0 else f"is {distance * 1000:.1f} mm from"
    scene = problem.checker.scene
    if scene.owner_of(first) == scene.owner_of(second):
        keeps = f"an arm's links keep {margin * 1000:g} mm from each other"
    else:
        keeps = f"clearance {problem.clearance_m * 1000:g} mm"
        physics = margin - problem.clearance_m
        if physics > 1e-9:  # PyBullet collides these shapes grown by its margin
            keeps += f" + {physics * 1000:g} mm of the physics' collision margin"
    return PlanningFailed(
        reason,
        f"{first} {where} {second} ({keeps})",
        arms=problem.arms,
        links=(first, second),
        problem=problem,
    )
