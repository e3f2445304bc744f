"""Planner choice: OMPL 2.x against RoboPlan on the same problems in the shared cell.

Both run RRT-Connect and then their own path shortening (OMPL's PathSimplifier,
RoboPlan's PathShortcutter) on a fixed, seeded set of problems in
launch_specs/shared_cell.yaml (benchmarks/cell_problems.py): half move one Panda
across the table, the other standing where it is; half move both jointly (14 joints).

Same collision model on both sides: the arms' collision meshes, the spec's objects
as primitives, the floor, and the same pairs left out (benchmarks/cell_model.py). On
random states the two models agree (checked at start, printed). OMPL checks states
through Pinocchio's broadphase with a margin; RoboPlan has no margin option, so it
plans against plain contact. Both check motions at the same resolution. Three more
rows separate the library from the settings: OMPL without margin (RoboPlan's
model exactly), OMPL with a cheap shortening pass instead of simplifyMax, and
RoboPlan checking motions 5x finer.

Every returned path is re-checked at a fine resolution without margin against the
reference model: a path that touches something there would hit it in PyBullet.
It prints the table and the ratios and writes benchmarks/results/planner_choice.json.

    python benchmarks/planner_choice.py                 # 200 problems (~2 minutes)
    python benchmarks/planner_choice.py --short         # 6 problems (CI)
    python benchmarks/planner_choice.py --problems 400
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import enum
import itertools
import json
import os
import platform
import statistics
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from armfleet.messages import FloatArray
from armfleet.objects import Shape
from cell_model import CellModel, Checker  # benchmarks/ is the script's folder
from cell_problems import CellProblem, ProblemSet

from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

try:  # an optional extra: armfleet[bench]
    import roboplan.core as rp_core
    import roboplan.rrt as rp_rrt

    HAVE_ROBOPLAN = True
except ImportError:
    HAVE_ROBOPLAN = False

RESULTS = Path(__file__).resolve().parent / "results"
SPEC = Path(__file__).resolve().parents[1] / "launch_specs" / "shared_cell.yaml"
#: Planning margin between different bodies for OMPL's checker [m] (issue 16's default).
MARGIN_M = 0.01
#: Motion-check resolution of both planners, a fraction of the state space's extent.
RESOLUTION = 0.005
#: Re-check resolution of returned paths (5x finer than planning), without margin.
FINE_RESOLUTION = 0.001
TIMEOUT_S = 1.0
#: States compared between the two collision models before the run.
AGREEMENT_SAMPLES = 2000


@dataclass
class Attempt:
    """One planner on one problem.

    Attributes:
        planner: planner name.
        problem: problem index.
        kind: ``"1 arm"`` or ``"2 arms"``.
        solved: an exact path was returned within the timeout.
        plan_ms: wall time of the search [ms].
        simplify_ms: wall time of the path shortening [ms].
        length_ratio: joint-space length of the returned path over the straight line's.
        touches: the returned path touches something at the fine re-check (reference model).
        touches_own_model: the same, re-checked with the planner's own collision model.
        checks: state checks made by the planner (search and shortening), where it can tell.
        check_ms: wall time spent in those checks [ms].
        recheck_ms: wall time of the fine re-check of the returned path [ms].
        error: why nothing came back.
    """

    planner: str
    problem: int
    kind: str
    solved: bool
    plan_ms: float = 0.0
    simplify_ms: float = 0.0
    length_ratio: float | None = None
    touches: bool | None = None
    touches_own_model: bool | None = None
    checks: int | None = None
    check_ms: float | None = None
    recheck_ms: float | None = None
    error: str = ""


def extent(cell: CellModel, problem: CellProblem) -> float:
    """Largest joint-space distance in the problem's bounds (OMPL's maximum extent) [rad]."""
    lower = np.concatenate([cell.arms[a].lower for a in problem.arms])
    upper = np.concatenate([cell.arms[a].upper for a in problem.arms])
    return float(np.linalg.norm(upper - lower))


class Shortening(enum.Enum):
    """How OMPL shortens a path once found."""

    MAX = "simplifyMax"  # PathSimplifier.simplifyMax: every pass until nothing improves
    SHORTCUT = "shortcut"  # reduceVertices then ropeShortcutPath: one cheap pass each


class OmplPlanner:
    """OMPL's RRTConnect, then its PathSimplifier, over the planned joints.

    Args:
        name: row name in the report.
        cell: the reference model.
        checker: the checker the planner uses (its margin).
        shortening: how the found path is shortened.
    """

    def __init__(
        self, name: str, cell: CellModel, checker: Checker, shortening: Shortening
    ) -> None:
        self.name = name
        self._cell = cell
        self._checker = checker
        self._shortening = shortening

    def attempt(self, problem: CellProblem) -> tuple[Attempt, list[FloatArray]]:
        cell, checker = self._cell, self._checker
        n = problem.start.size
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        lower = np.concatenate([cell.arms[a].lower for a in problem.arms])
        upper = np.concatenate([cell.arms[a].upper for a in problem.arms])
        for i in range(n):
            bounds.setLow(i, float(lower[i]))
            bounds.setHigh(i, float(upper[i]))
        space.setBounds(bounds)
        setup = og.SimpleSetup(space)
        si = setup.getSpaceInformation()
        q = problem.q_full.copy()
        indices = cell.indices(problem.arms)

        def valid(state: Any) -> bool:
            q[indices] = state[0:n]
            return not checker.collides(q)

        setup.setStateValidityChecker(valid)
        si.setStateValidityCheckingResolution(RESOLUTION)
        setup.setPlanner(og.RRTConnect(si))
        start, goal = space.allocState(), space.allocState()
        start[0:n] = problem.start.tolist()
        goal[0:n] = problem.goal.tolist()
        setup.setStartAndGoalStates(start, goal)
        setup.setup()
        checks, check_s = checker.checks, checker.seconds
        started = time.perf_counter()
        setup.solve(TIMEOUT_S)
        plan_ms = (time.perf_counter() - started) * 1e3
        result = Attempt(self.name, problem.index, problem.kind, False, plan_ms)
        if not setup.haveExactSolutionPath():
            result.error = "no exact path within the timeout"
            return result, []
        path = setup.getSolutionPath()
        simplifier = setup.getPathSimplifier()
        started = time.perf_counter()
        if self._shortening is Shortening.MAX:
            simplifier.simplifyMax(path)
        else:
            simplifier.reduceVertices(path)
            simplifier.ropeShortcutPath(path)
        result.simplify_ms = (time.perf_counter() - started) * 1e3
        result.solved = True
        result.checks = checker.checks - checks
        result.check_ms = (checker.seconds - check_s) * 1e3
        states = [np.array(path.getState(i)[0:n]) for i in range(path.getStateCount())]
        return result, states


class RoboPlanPlanner:
    """RoboPlan's RRT (RRT-Connect) and PathShortcutter on one URDF of every arm.

    The scene gets the same objects, floor and left-out pairs as the reference model.

    Args:
        name: row name in the report.
        world: the world whose arms and objects are planned around.
        cell: the reference model (the pairs it leaves out; joint order).
        seed: seed of the planner's random numbers.
        resolution: motion-check step, a fraction of the state space's extent.
    """

    def __init__(
        self, name: str, world: armfleet.World, cell: CellModel, seed: int, resolution: float
    ) -> None:
        self.name = name
        self._resolution = resolution
        scene = rp_core.Scene("cell", rp_core.loadUrdfSceneDescriptionFromXml(one_urdf(world)))
        for label, thing in world.objects.items():  # as cell_model: boxes, cylinders, spheres
            spec, color = thing.spec, np.array(thing.color)
            if spec.shape is Shape.BOX:
                scene.addBoxGeometry(label, "world", rp_core.Box(*spec.size), thing.pose, color)
            elif spec.shape is Shape.CYLINDER:
                cylinder = rp_core.Cylinder(*spec.size)
                scene.addCylinderGeometry(label, "world", cylinder, thing.pose, color)
            else:
                sphere = rp_core.Sphere(spec.size[0])
                scene.addSphereGeometry(label, "world", sphere, thing.pose, color)
        floor = np.eye(4)
        floor[2, 3] = -0.05  # a 10 cm slab whose top is the floor
        scene.addBoxGeometry("floor", "world", rp_core.Box(10, 10, 0.1), floor, np.ones(4))
        left_out = [(a, b) for a, b in (sorted(p) for p in cell.unchecked_pairs if len(p) == 2)]
        scene.setCollisions(left_out, False)
        for arm in world.arms.values():
            scene.addGroup(arm.name, list(arm.joint_names))
        scene.addGroup(
            "+".join(world.arms), [j for a in world.arms.values() for j in a.joint_names]
        )
        model = cell.model
        self._order = [model.joints[model.getJointId(j)].idx_q for j in scene.getJointNames()]
        self._scene = scene
        self._cell = cell
        self._seed = seed
        self._joint_names = {arm.name: list(arm.joint_names) for arm in world.arms.values()}

    def full(self, q_full: FloatArray) -> FloatArray:
        """The scene's joint positions for the reference model's configuration."""
        return q_full[self._order]

    def collides(self, q_full: FloatArray) -> bool:
        return bool(self._scene.hasCollisions(self.full(q_full)))

    def attempt(self, problem: CellProblem) -> tuple[Attempt, list[FloatArray]]:
        scene, group = self._scene, "+".join(problem.arms)
        scene.setJointPositions(self.full(problem.q_full))
        step = self._resolution * extent(self._cell, problem)
        options = rp_rrt.RRTOptions(
            group_name=group,
            max_nodes=1_000_000,
            max_connection_distance=0.2 * extent(self._cell, problem),  # OMPL's default range
            collision_check_step_size=step,
            max_planning_time=TIMEOUT_S,
            rrt_connect=True,
        )
        planner = rp_rrt.RRT(scene, options)
        planner.setRngSeed(self._seed + problem.index)
        names = [j for arm in problem.arms for j in self._joint_names[arm]]
        start = rp_core.JointConfiguration(names, problem.start)
        goal = rp_core.JointConfiguration(names, problem.goal)
        started = time.perf_counter()
        try:
            path = planner.plan(start, goal)
        except RuntimeError as exc:  # RoboPlan's answer to a timeout
            plan_ms = (time.perf_counter() - started) * 1e3
            error = " ".join(str(exc).split())
            return Attempt(self.name, problem.index, problem.kind, False, plan_ms, error=error), []
        plan_ms = (time.perf_counter() - started) * 1e3
        shortcutter = rp_core.PathShortcutter(
            scene,
            rp_core.PathShortcuttingOptions(group_name=group, max_step_size=step, seed=self._seed),
        )
        started = time.perf_counter()
        path = shortcutter.shortcut(path)
        simplify_ms = (time.perf_counter() - started) * 1e3
        states = [np.asarray(q) for q in path.positions]
        return Attempt(self.name, problem.index, problem.kind, True, plan_ms, simplify_ms), states

    def touches(self, problem: CellProblem, states: list[FloatArray], step: float) -> bool:
        """Whether the path touches something in RoboPlan's own model, checked every ``step``."""
        scene, group = self._scene, "+".join(problem.arms)
        scene.setJointPositions(self.full(problem.q_full))
        full = [scene.toFullJointPositions(group, q) for q in states]
        return any(
            rp_core.hasCollisionsAlongPath(scene, a, b, step) for a, b in itertools.pairwise(full)
        )


def one_urdf(world: armfleet.World) -> str:
    """Every arm of ``world`` in one URDF (one ``world`` link; visuals dropped)."""
    robot = ET.Element("robot", name="cell")
    ET.SubElement(robot, "link", name="world")
    materials: set[str] = set()
    for arm in world.arms.values():
        for element in ET.fromstring(arm.description.urdf):
            if element.tag == "link" and element.get("name") == "world":
                continue
            if element.tag == "material":
                if element.get("name") in materials:
                    continue
                materials.add(element.get("name", ""))
            for visual in element.findall("visual"):
                element.remove(visual)
            robot.append(element)
    return ET.tostring(robot, encoding="unicode")


def path_length(states: list[FloatArray]) -> float:
    return float(sum(np.linalg.norm(b - a) for a, b in itertools.pairwise(states)))


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else float("nan")


def summarise(attempts: list[Attempt]) -> dict[str, Any]:
    """Success, times and quality of one planner on one class of problems."""
    solved = [a for a in attempts if a.solved]
    plan = [a.plan_ms for a in solved]
    row: dict[str, Any] = {
        "problems": len(attempts),
        "solved": len(solved),
        "success_rate": round(len(solved) / len(attempts), 4) if attempts else None,
        "plan_ms_median": round(percentile(plan, 50), 2),
        "plan_ms_p95": round(percentile(plan, 95), 2),
        "simplify_ms_median": round(percentile([a.simplify_ms for a in solved], 50), 2),
        "simplify_ms_p95": round(percentile([a.simplify_ms for a in solved], 95), 2),
        "length_ratio_median": round(percentile([a.length_ratio or 0 for a in solved], 50), 3),
        "length_ratio_p95": round(percentile([a.length_ratio or 0 for a in solved], 95), 3),
        "touching_paths": sum(bool(a.touches) for a in solved),
        "touching_fraction": round(sum(bool(a.touches) for a in solved) / len(solved), 4)
        if solved
        else None,
        "touching_paths_own_model": sum(bool(a.touches_own_model) for a in solved),
        "recheck_ms_median": round(percentile([a.recheck_ms or 0 for a in solved], 50), 2),
    }
    checks = [a.checks for a in solved if a.checks is not None]
    if checks:
        row["checks_median"] = int(statistics.median(checks))
        check_ms = sum(a.check_ms or 0.0 for a in solved)
        row["check_share"] = round(check_ms / sum(a.plan_ms + a.simplify_ms for a in solved), 3)
    return row


def agreement(cell: CellModel, reference: Checker, roboplan: RoboPlanPlanner, seed: int) -> int:
    """States (of ``AGREEMENT_SAMPLES`` random ones) where the two models disagree."""
    rng = np.random.default_rng(seed)
    names = list(cell.arms)
    indices = cell.indices(names)
    lower = np.concatenate([cell.arms[a].lower for a in names])
    upper = np.concatenate([cell.arms[a].upper for a in names])
    q = cell.q
    disagree = 0
    for _ in range(AGREEMENT_SAMPLES):
        q[indices] = rng.uniform(lower, upper)
        disagree += reference.collides(q) != roboplan.collides(q)
    return disagree


Planner = OmplPlanner | RoboPlanPlanner


def planners(world: armfleet.World, cell: CellModel, seed: int) -> dict[Planner, str]:
    """The variants measured, each with what it is."""
    margin = cell.checker(MARGIN_M)
    return {
        OmplPlanner("OMPL", cell, margin, Shortening.MAX): (
            f"RRTConnect, {MARGIN_M * 1e3:.0f} mm margin, PathSimplifier.simplifyMax"
        ),
        OmplPlanner("OMPL-cut", cell, cell.checker(MARGIN_M), Shortening.SHORTCUT): (
            f"RRTConnect, {MARGIN_M * 1e3:.0f} mm margin, reduceVertices + ropeShortcutPath"
        ),
        OmplPlanner("OMPL-0mm", cell, cell.checker(0.0), Shortening.MAX): (
            "RRTConnect, no margin (as RoboPlan), PathSimplifier.simplifyMax"
        ),
        RoboPlanPlanner("RoboPlan", world, cell, seed, RESOLUTION): (
            f"RRT-Connect + PathShortcutter, no margin, steps of {RESOLUTION:.1%}"
        ),
        RoboPlanPlanner("RP-fine", world, cell, seed, FINE_RESOLUTION): (
            f"RRT-Connect + PathShortcutter, no margin, steps of {FINE_RESOLUTION:.1%}"
        ),
    }


def run(count: int, seed: int) -> dict[str, Any]:
    load_at_start = [round(x, 2) for x in os.getloadavg()]  # other work on the machine
    ou.setLogLevel(ou.LogLevel.LOG_ERROR)
    ou.RNG.setSeed(seed)
    world = armfleet.launch(SPEC, viewer=False)
    try:
        cell = CellModel(world)
        reference = cell.checker(0.0)
        started = time.perf_counter()
        problems = ProblemSet(cell, cell.checker(MARGIN_M), seed).problems(count)
        print(f"{count} problems in {time.perf_counter() - started:.1f} s", flush=True)
        variants = planners(world, cell, seed)
    finally:
        world.close()
    roboplan = next(p for p in variants if isinstance(p, RoboPlanPlanner))
    disagree = agreement(cell, reference, roboplan, seed)
    straight: dict[str, list[bool]] = {}
    attempts: list[Attempt] = []
    for problem in problems:
        fine = FINE_RESOLUTION * extent(cell, problem)
        indices = cell.indices(problem.arms)
        line = [problem.start, problem.goal]
        hit = reference.first_contact_on_path(problem.q_full, indices, line, fine)
        straight.setdefault(problem.kind, []).append(hit is not None)
        straight_length = float(np.linalg.norm(problem.goal - problem.start))
        for planner in variants:
            attempt, states = planner.attempt(problem)
            if attempt.solved:
                attempt.length_ratio = round(path_length(states) / straight_length, 4)
                started = time.perf_counter()
                hit = reference.first_contact_on_path(problem.q_full, indices, states, fine)
                attempt.recheck_ms = (time.perf_counter() - started) * 1e3
                attempt.touches = hit is not None
                if isinstance(planner, RoboPlanPlanner):
                    attempt.touches_own_model = planner.touches(problem, states, fine)
            attempts.append(attempt)
        if (problem.index + 1) % 50 == 0:
            print(f"  {problem.index + 1}/{count}", flush=True)
    kinds = sorted(straight)
    rows = [
        {"planner": planner.name, "kind": kind}
        | summarise([a for a in attempts if a.planner == planner.name and a.kind == kind])
        for planner in variants
        for kind in kinds
    ]
    everything = [hit for hits in straight.values() for hit in hits]
    return {
        "machine": {
            "python": platform.python_version(),
            "processor": platform.machine(),
            "cpus": os.cpu_count(),
            "load_average_at_start": load_at_start,
            "load_average_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "settings": {
            "spec": SPEC.name,
            "problems": count,
            "seed": seed,
            "timeout_s": TIMEOUT_S,
            "margin_m": MARGIN_M,
            "motion_check_resolution": RESOLUTION,
            "fine_recheck_resolution": FINE_RESOLUTION,
            "collision_pairs": cell.pair_count,
            "model_disagreements": f"{disagree}/{AGREEMENT_SAMPLES}",
        },
        "planners": {planner.name: text for planner, text in variants.items()},
        "straight_line_collides": {kind: round(sum(v) / len(v), 4) for kind, v in straight.items()}
        | {"all": round(sum(everything) / len(everything), 4)},
        "rows": rows,
        "attempts": [asdict(a) for a in attempts],
    }


def print_report(figures: dict[str, Any]) -> None:
    settings = figures["settings"]
    print(
        f"\nshared cell, {settings['problems']} problems, seed {settings['seed']}, timeout "
        f"{settings['timeout_s']} s, motion checks every {settings['motion_check_resolution']:.1%}"
        f" of the state space's extent; every returned path re-checked every "
        f"{settings['fine_recheck_resolution']:.1%}, without margin"
    )
    machine = figures["machine"]
    print(
        f"{machine['cpus']} CPUs, load average {machine['load_average_at_start'][0]} at the "
        f"start, {machine['load_average_at_end'][0]} at the end"
    )
    print(
        f"collision models (reference, RoboPlan's) disagree on "
        f"{settings['model_disagreements']} random states"
    )
    for name, text in figures["planners"].items():
        print(f"  {name:<9} {text}")
    line = figures["straight_line_collides"]
    print(
        "straight joint-space line collides: " + ", ".join(f"{k} {v:.0%}" for k, v in line.items())
    )
    print(
        f"{'planner':<9} {'class':<7} {'solved':>9} {'plan med':>9} {'plan p95':>9} "
        f"{'short med':>10} {'short p95':>10} {'length':>7} {'touching':>9} {'own model':>10} "
        f"{'checks':>7} {'in checks':>10}"
    )
    for row in figures["rows"]:
        own = row["touching_paths_own_model"] if row["planner"].startswith("R") else "-"
        checks = row.get("checks_median", "-")
        share = f"{row['check_share']:.0%}" if "check_share" in row else "-"
        print(
            f"{row['planner']:<9} {row['kind']:<7} {row['solved']:>4}/{row['problems']:<4} "
            f"{row['plan_ms_median']:>7.1f}ms {row['plan_ms_p95']:>7.1f}ms "
            f"{row['simplify_ms_median']:>8.1f}ms {row['simplify_ms_p95']:>8.1f}ms "
            f"{row['length_ratio_median']:>6.2f}x {row['touching_paths']:>9} {own:>10} "
            f"{checks:>7} {share:>10}"
        )
    by = {(r["planner"], r["kind"]): r for r in figures["rows"]}
    for kind in sorted({r["kind"] for r in figures["rows"]}):
        ompl = by[("OMPL", kind)]
        for name in figures["planners"]:
            if name == "OMPL":
                continue
            other = by[(name, kind)]
            total = other["plan_ms_median"] + other["simplify_ms_median"]
            print(
                f"{name}/OMPL, {kind}: plan median "
                f"{other['plan_ms_median'] / ompl['plan_ms_median']:.2f}x, p95 "
                f"{other['plan_ms_p95'] / ompl['plan_ms_p95']:.2f}x, shortening "
                f"{other['simplify_ms_median'] / ompl['simplify_ms_median']:.2f}x, plan + "
                f"shortening {total / (ompl['plan_ms_median'] + ompl['simplify_ms_median']):.2f}x, "
                f"length {other['length_ratio_median'] / ompl['length_ratio_median']:.2f}x"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--short", action="store_true", help="6 problems (CI)")
    parser.add_argument("--problems", type=int, default=200, help="problems (default 200)")
    parser.add_argument("--seed", type=int, default=16)
    parser.add_argument("--json", type=Path, default=RESULTS / "planner_choice.json")
    args = parser.parse_args()
    if not HAVE_ROBOPLAN:
        print("planner_choice needs roboplan: pip install -e .[bench]", file=sys.stderr)
        sys.exit(2)
    if args.problems < 2:
        parser.error("--problems: at least 2 (one of each class)")
    figures = run(6 if args.short else args.problems, args.seed)
    print_report(figures)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(figures, indent=1))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
