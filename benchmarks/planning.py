"""Planning benchmark: collision-free plans in the shared cell, against straight motions.

The problems are benchmarks/cell_problems.py's fixed, seeded set in
launch_specs/shared_cell.yaml (the same as benchmarks/planner_choice.py's for one
seed): half move one Panda to the other half of the table (the other arm stands
still, an obstacle), half move both jointly (14 joints). Every third problem gives
its goal as tool0 poses in the world (the pose of the drawn joint goal), so the
request includes IK.

Two worlds are made from the spec, headless:

- **planned**: for each problem, the arms are brought up again at its start
  (``world.remove`` / ``world.spawn(initial_positions=...)``: a running arm cannot be
  teleported, and planned moves to each start would double the simulated time), one
  untimed request lets the planner build its scene for the new arms (as a running
  world does once when arms come or go; reported as ``scene_build_ms``), then the
  request is timed (``world.plan(targets)``: IK,
  scene, search, simplification, proof of clearance, timing), in wall time and in CPU
  time of the process (``time.process_time``: what the request cost, whatever else
  the machine was doing), and executed in PyBullet,
  with every contact of an arm on ``/collisions`` counted (with the other arm, itself,
  the floor, the table, post and walls, and the movable cubes) and protective stops on.
  Each returned path is also re-checked independently of the planner: sampled every
  ``RECHECK_STEP_RAD`` against benchmarks/cell_model.py's model, without margin.
  The motion's duration is the plan's (``plan.duration_s``, as executed), and the same
  waypoints are timed rest to rest, segment by segment (``TimedPath``, the timing
  before issue 27), for the comparison.
- **straight**: for each problem, the arms are brought up again at its start (cubes
  put back where pushed), then the same targets go to straight ``world.move_together``;
  a collision is any contact of an arm (protective stops counted too).

It prints a table per class (1 arm, 2 arms), the issue's targets with pass/miss and
where the planning time goes, the comparison with VAMP (benchmarks/planning_report.py
says which figures of VAMP's it uses), and writes benchmarks/results/planning.json.

    python benchmarks/planning.py               # 200 problems (a few minutes)
    python benchmarks/planning.py --short       # 4 problems (CI)
    python benchmarks/planning.py --budget 2000 # plans bounded by iterations, not time
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import json
import logging
import os
import platform
import subprocess
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from armfleet.planning.scene import BULLET_MARGIN_M
from armfleet.messages import FloatArray
from armfleet.planning.path_timing import JointLimits, TimedPath
from armfleet.spec import FleetSpec, load_spec
from cell_execution import ContactLog, respawn_at, run_until_still
from cell_model import CellModel, Checker  # benchmarks/ is the script's folder
from cell_problems import CellProblem, ProblemSet
from planning_report import print_report, summarise, targets, vamp_comparison

RESULTS = Path(__file__).resolve().parent / "results"
SPEC = Path(__file__).resolve().parents[1] / "launch_specs" / "shared_cell.yaml"
#: Margin of the problem set's starts and goals [m]: the planner's default clearance, plus
#: the physics' collision margin of two meshes, which the planner keeps too.
PROBLEM_MARGIN_M = 0.01 + 2 * BULLET_MARGIN_M
#: Every this many problems, one has pose goals (the others joint goals).
POSE_EVERY = 3
#: Joint-space step of the independent re-check of returned paths [rad]; a Panda's
#: points move at most ~2 mm per 1e-3 rad of joint-space distance.
RECHECK_STEP_RAD = 1e-3


@dataclass
class Straight:
    """The straight ``move_together`` on one problem.

    Attributes:
        refused: why the world refused the motion (an unreachable pose), else "".
        contact_steps: physics steps with a contact of an arm.
        pairs: what touched.
        stops: protective stops.
        deepest_mm: deepest penetration [mm].
    """

    refused: str = ""
    contact_steps: int = 0
    pairs: list[str] = field(default_factory=list)
    stops: int = 0
    deepest_mm: float = 0.0

    @property
    def collided(self) -> bool:
        return self.contact_steps > 0 or self.stops > 0


@dataclass
class Outcome:
    """One problem: the plan, its execution, and the straight motion.

    Attributes:
        index, kind, arms, goal: the problem (``goal``: ``"joint"`` or ``"pose"``).
        starts: every arm's start [rad]; targets: per planned arm, its joint goal
            [rad] or its tool0 pose (4x4, world).
        attempted: the arms reached the start (else ``error`` says why).
        solved: a plan was returned.
        error: the failure's one line.
        reason: the :class:`~armfleet.planning.FailureReason` value, or "".
        request_ms: wall time of ``world.plan`` [ms]; request_cpu_ms: the CPU time
            of the process during it [ms]; planner_ms: the plan's own
            ``planning_time_s`` [ms].
        phases_ms: the plan's time per phase [ms].
        checks, samples, waypoints: what the plan cost and is.
        straight_clear: the planner proved the straight line clear (no search).
        length_ratio: path length over the straight joint line to the goal state.
        recheck_touches: the independent re-check found a touching state.
        contact_steps, pairs, stops, deepest_mm: execution in PyBullet.
        tracking_error_rad: largest joint error at the end of the motion [rad].
        duration_s: the plan's duration, as executed [s]; rest_to_rest_s: its
            waypoints timed rest to rest, segment by segment [s].
        pose_error_mm, pose_error_deg: tool0 at the end against the pose goal.
        scene_build_ms: the untimed request after the arms were brought up at the
            start, in which the planner builds its scene for the new arms [ms].
        straight: the straight motion on the same problem.
    """

    index: int
    kind: str
    arms: list[str]
    goal: str
    starts: dict[str, list[float]]
    targets: dict[str, list[Any]]
    attempted: bool = False
    solved: bool = False
    error: str = ""
    reason: str = ""
    request_ms: float = 0.0
    request_cpu_ms: float = 0.0
    planner_ms: float = 0.0
    phases_ms: dict[str, float] = field(default_factory=dict)
    checks: int = 0
    samples: int = 0
    waypoints: int = 0
    straight_clear: bool = False
    length_ratio: float | None = None
    recheck_touches: bool | None = None
    contact_steps: int = 0
    pairs: list[str] = field(default_factory=list)
    stops: int = 0
    deepest_mm: float = 0.0
    tracking_error_rad: float | None = None
    duration_s: float | None = None
    rest_to_rest_s: float | None = None
    scene_build_ms: float = 0.0
    pose_error_mm: float | None = None
    pose_error_deg: float | None = None
    straight: Straight = field(default_factory=Straight)


class Cell:
    """The problems' collision model, and what the benchmark computes with it.

    Args:
        model: the cell's reference model (benchmarks/cell_model.py).
    """

    def __init__(self, model: CellModel) -> None:
        self.model = model
        self.reference: Checker = model.checker(0.0)
        self._data = model.model.createData()

    def starts(self, problem: CellProblem) -> dict[str, FloatArray]:
        """Every arm's joint positions at the problem's start."""
        return {name: problem.q_full[list(a.q_indices)] for name, a in self.model.arms.items()}

    def q_with(self, problem: CellProblem, values: FloatArray) -> FloatArray:
        """The problem's start with its planned arms at ``values``."""
        q = problem.q_full.copy()
        q[self.model.indices(problem.arms)] = values
        return q

    def tool_pose(self, q: FloatArray, arm: str) -> pin.SE3:
        model = self.model.model
        pin.framesForwardKinematics(model, self._data, q)
        return pin.SE3(self._data.oMf[model.getFrameId(f"{arm}_tool0")])

    def targets(self, problem: CellProblem, pose: bool) -> dict[str, Any]:
        """Per planned arm: its joint goal, or the tool0 pose it has there (4x4)."""
        q_goal = self.q_with(problem, problem.goal)
        targets: dict[str, Any] = {}
        for k, arm in enumerate(problem.arms):
            if pose:
                targets[arm] = self.tool_pose(q_goal, arm).homogeneous
            else:
                targets[arm] = problem.goal[7 * k : 7 * (k + 1)]
        return targets

    def recheck(self, problem: CellProblem, waypoints: FloatArray) -> bool:
        """Whether the path touches anything, sampled every ``RECHECK_STEP_RAD``."""
        indices = self.model.indices(problem.arms)
        hit = self.reference.first_contact_on_path(
            problem.q_full, indices, list(waypoints), RECHECK_STEP_RAD
        )
        return hit is not None


def make_problems(world: armfleet.World, count: int, seed: int) -> tuple[Cell, list[CellProblem]]:
    model = CellModel(world)
    problems = ProblemSet(model, model.checker(PROBLEM_MARGIN_M), seed).problems(count)
    return Cell(model), problems


def planned_pass(
    spec: FleetSpec, cell: Cell, problems: list[CellProblem], limit: dict[str, Any]
) -> list[Outcome]:
    """Plan and execute every problem in one world; see the module's docstring."""
    outcomes = []
    world = armfleet.launch(spec, viewer=False)
    try:
        log = ContactLog(world)
        for problem in problems:
            pose = problem.index % POSE_EVERY == POSE_EVERY - 1
            targets = cell.targets(problem, pose)
            starts = cell.starts(problem)
            outcome = Outcome(
                problem.index,
                problem.kind,
                list(problem.arms),
                "pose" if pose else "joint",
                {name: values.round(6).tolist() for name, values in starts.items()},
                {name: np.asarray(t).round(6).tolist() for name, t in targets.items()},
            )
            outcomes.append(outcome)
            try:
                respawn_at(world, spec, starts)
                # The arms are new: the planner builds its scene (and the checker of the
                # problem's arms) again, once, as a long-running world does when arms
                # come and go. Not part of the figures.
                began = time.perf_counter()
                world.plan({name: world.arm(name).positions for name in problem.arms})
                outcome.scene_build_ms = (time.perf_counter() - began) * 1e3
            except armfleet.ArmfleetError as exc:
                outcome.error, outcome.reason = f"could not start: {exc}", "could not start"
                continue
            log.take()
            outcome.attempted = True
            plan_and_execute(world, log, cell, problem, targets, outcome, limit)
            if (problem.index + 1) % 25 == 0:
                print(f"  planned {problem.index + 1}/{len(problems)}", flush=True)
    finally:
        world.close()
    return outcomes


def plan_and_execute(
    world: armfleet.World,
    log: ContactLog,
    cell: Cell,
    problem: CellProblem,
    targets: dict[str, Any],
    outcome: Outcome,
    limit: dict[str, Any],
) -> None:
    """Time ``world.plan(targets, **limit)`` (wall and CPU), check and run its plan."""
    began, cpu = time.perf_counter(), time.process_time()

    def timed() -> None:
        outcome.request_ms = (time.perf_counter() - began) * 1e3
        outcome.request_cpu_ms = (time.process_time() - cpu) * 1e3

    try:
        plan = world.plan(targets, **limit)
    except armfleet.PlanningFailed as exc:
        timed()
        outcome.error, outcome.reason = str(exc), exc.reason.value
        return
    except armfleet.ArmfleetError as exc:  # not a planning failure: kept, counted, shown
        timed()
        outcome.error, outcome.reason = str(exc), type(exc).__name__
        return
    timed()
    outcome.solved = True
    outcome.planner_ms = plan.planning_time_s * 1e3
    outcome.phases_ms = {k: round(v * 1e3, 4) for k, v in plan.seconds.items()}
    outcome.checks, outcome.samples = plan.collision_checks, plan.samples
    outcome.waypoints = len(plan.waypoints)
    outcome.straight_clear = plan.samples == 0 and len(plan.waypoints) == 2
    line = float(np.linalg.norm(plan.waypoints[-1] - plan.waypoints[0]))
    outcome.length_ratio = round(plan.length_rad / line, 4) if line > 0 else 1.0
    outcome.recheck_touches = cell.recheck(problem, plan.waypoints)
    outcome.duration_s = round(plan.duration_s, 4)
    rest_to_rest = TimedPath(plan.waypoints, joint_limits(world, plan.arms))
    outcome.rest_to_rest_s = round(rest_to_rest.duration, 4)
    stops = world.safety.stops
    try:
        duration = world.execute(plan)
    except armfleet.ArmfleetError as exc:
        outcome.solved = False
        outcome.error, outcome.reason = f"execute: {exc}", "execute refused"
        return
    run_until_still(world, duration)
    touches = log.take()
    outcome.contact_steps, outcome.pairs = touches.steps, sorted("/".join(p) for p in touches.pairs)
    outcome.deepest_mm = round(touches.deepest_m * 1e3, 3)
    outcome.stops = world.safety.stops - stops
    reached = np.concatenate([world.arm(name).positions for name in plan.arms])
    outcome.tracking_error_rad = float(np.max(np.abs(reached - plan.waypoints[-1])))
    if outcome.goal == "pose":
        q = cell.q_with(problem, reached)
        errors = [cell.tool_pose(q, arm).actInv(pin.SE3(targets[arm])) for arm in plan.arms]
        outcome.pose_error_mm = max(float(np.linalg.norm(e.translation)) * 1e3 for e in errors)
        outcome.pose_error_deg = max(
            float(np.degrees(np.linalg.norm(pin.log3(e.rotation)))) for e in errors
        )


def joint_limits(world: armfleet.World, arms: tuple[str, ...]) -> JointLimits:
    """The planned joints' velocity, acceleration and jerk limits (their controllers')."""
    velocity, acceleration, jerk = [], [], []
    for name in arms:
        controller = world.arm(name).position_controller
        n = controller.lower.size
        velocity.append(controller.max_velocity)
        acceleration.append(np.full(n, float(controller.parameters["max_acceleration_rad_s2"])))
        jerk.append(np.full(n, float(controller.parameters["max_jerk_rad_s3"])))
    return JointLimits(np.concatenate(velocity), np.concatenate(acceleration), np.concatenate(jerk))


def straight_pass(spec: FleetSpec, cell: Cell, problems: list[CellProblem]) -> list[Straight]:
    """Straight ``move_together`` on every problem, each from a fresh start.

    The protective stops it provokes are counted, not logged.
    """
    results = []
    world = armfleet.launch(spec, viewer=False)
    logger = logging.getLogger("armfleet")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        log = ContactLog(world)
        for problem in problems:
            pose = problem.index % POSE_EVERY == POSE_EVERY - 1
            respawn_at(world, spec, cell.starts(problem))
            log.take()
            stops = world.safety.stops
            result = Straight()
            try:
                duration = world.move_together(cell.targets(problem, pose))
            except armfleet.ArmfleetError as exc:
                result.refused = str(exc)
                results.append(result)
                continue
            run_until_still(world, duration)
            touches = log.take()
            result.contact_steps = touches.steps
            result.pairs = sorted("/".join(p) for p in touches.pairs)
            result.deepest_mm = round(touches.deepest_m * 1e3, 3)
            result.stops = world.safety.stops - stops
            results.append(result)
    finally:
        logger.setLevel(level)
        world.close()
    return results


def source_version() -> dict[str, Any]:
    """The commit measured, and whether armfleet/planning/ differs from it."""
    root = Path(__file__).resolve().parents[1]

    def git(*args: str) -> str:
        result = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True)
        return result.stdout.strip() if result.returncode == 0 else ""

    return {
        "commit": git("rev-parse", "--short", "HEAD"),
        "planning_changed_since": bool(git("status", "--porcelain", "armfleet/planning")),
    }


def run(count: int, seed: int, budget: int | None = None) -> dict[str, Any]:
    spec = load_spec(SPEC)
    load_before = os.getloadavg()[0]
    world = armfleet.launch(spec, viewer=False)
    try:
        started = time.perf_counter()
        cell, problems = make_problems(world, count, seed)
        print(f"{count} problems in {time.perf_counter() - started:.1f} s", flush=True)
    finally:
        world.close()
    started = time.perf_counter()
    limit: dict[str, Any] = {"timeout_s": 1.0} if budget is None else {"budget": budget}
    outcomes = planned_pass(spec, cell, problems, limit)
    planned_s = time.perf_counter() - started
    started = time.perf_counter()
    for outcome, straight in zip(outcomes, straight_pass(spec, cell, problems), strict=True):
        outcome.straight = straight
    straight_s = time.perf_counter() - started
    records = [asdict(o) | {"straight_collided": o.straight.collided} for o in outcomes]
    classes = summarise(records)
    return {
        "machine": {"python": platform.python_version(), "processor": platform.machine()},
        "source": source_version(),
        "settings": {
            "spec": SPEC.name,
            "problems": count,
            "seed": seed,
            "pose_goals_every": POSE_EVERY,
            **limit,
            "clearance_m": 0.01,
            "recheck_step_rad": RECHECK_STEP_RAD,
            "recheck_us_per_state": round(
                cell.reference.seconds / max(1, cell.reference.checks) * 1e6, 1
            ),
            "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)],
            "wall_s": {
                "planned_world": round(planned_s, 1),
                "straight_world": round(straight_s, 1),
            },
        },
        "classes": classes,
        "targets": targets(classes),
        "vamp": vamp_comparison(classes),
        "problems": records,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--short", action="store_true", help="4 problems (CI)")
    parser.add_argument("--problems", type=int, default=200, help="problems (default 200)")
    parser.add_argument("--seed", type=int, default=16)
    parser.add_argument(
        "--budget", type=int, default=None, metavar="N",
        help="plan within N planner iterations (reproducible) instead of 1 s",
    )  # fmt: skip
    parser.add_argument("--json", type=Path, default=RESULTS / "planning.json")
    args = parser.parse_args()
    if args.problems < 2:
        parser.error("--problems: at least 2 (one of each class)")
    figures = run(4 if args.short else args.problems, args.seed, args.budget)
    print_report(figures)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(figures, indent=1))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
