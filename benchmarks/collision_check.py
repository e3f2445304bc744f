"""The planner's collision check and proof: compiled (cpp/planning_check.cpp) against Python.

In launch_specs/shared_cell.yaml (two Pandas, a table, a post, two walls, four cubes), in
one run, on the same inputs:

- **per state**: ``CollisionChecker.valid`` and ``.far`` on random states of one arm
  (the other an obstacle) and of both arms, the Python reference (Pinocchio's broadphase,
  called from Python) against the compiled check; µs per call (best of a few repeats: the
  machine is shared), and whether every answer agrees;
- **per segment**: ``PathCertifier.first_failure`` on the segments of paths the planner
  found for benchmarks/cell_problems.py's problems, µs per segment, same answers;
- **per request**: CPU ms of whole ``world.plan`` requests (IK, search, shortening, proof,
  timing) on those problems (joint goals), the planner using the compiled check or the
  Python one, interleaved problem by problem; medians and p95.

It prints the figures and the ratios, and writes benchmarks/results/collision_check.json.

    python benchmarks/collision_check.py --problems 20   # about a minute on 2 cores
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import json
import time
import timeit
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from armfleet.planning.scene import BULLET_MARGIN_M
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.scene import CollisionChecker, PlanningScene
from armfleet.spec import load_spec
from cell_execution import respawn_at  # benchmarks/ is the script's folder
from cell_model import CellModel
from cell_problems import ProblemSet

RESULTS = Path(__file__).resolve().parent / "results"
SPEC = Path(__file__).resolve().parents[1] / "launch_specs" / "shared_cell.yaml"
#: Margin of the problem set's starts and goals [m]: the planner's default clearance, plus
#: the physics' collision margin of two meshes, which the planner keeps too.
PROBLEM_MARGIN_M = 0.01 + 2 * BULLET_MARGIN_M
CLEARANCE_M = 0.01
STATES = 2000
REPEATS = 5


@contextmanager
def checkers(world: armfleet.World, arms: tuple[str, ...]) -> Iterator[tuple[Any, Any]]:
    """The planner's checkers of ``arms`` (its scene is private): compiled, Python."""
    planner = world._planner
    with planner._scenes.scene(planner._snapshot(CLEARANCE_M)) as scene:
        yield scene.checker(arms), scene.checker(arms, compiled=False)


def best_us(call: Callable[[], Any], count: int) -> float:
    """µs per item of ``call`` (which runs ``count`` items), best of ``REPEATS``."""
    return min(timeit.repeat(call, number=1, repeat=REPEATS)) / count * 1e6


def compare(
    ours: Callable[[Any], bool], theirs: Callable[[Any], bool], states: list[Any]
) -> dict[str, Any]:
    """Both checks on ``states``: µs per state and whether every answer agrees."""
    python = best_us(lambda: [theirs(s) for s in states], len(states))
    compiled = best_us(lambda: [ours(s) for s in states], len(states))
    return {
        "python_us": python,
        "compiled_us": compiled,
        "ratio": python / compiled,
        "agree": all(ours(s) == theirs(s) for s in states),
    }


def state_figures(world: armfleet.World, arms: tuple[str, ...]) -> dict[str, Any]:
    lower = np.concatenate([world.arm(a).position_controller.lower for a in arms])
    upper = np.concatenate([world.arm(a).position_controller.upper for a in arms])
    states = list(np.random.default_rng(0).uniform(lower, upper, (STATES, lower.size)))
    with checkers(world, arms) as (fast, reference):
        free = [s for s in states if reference.valid(s)]
        figures: dict[str, Any] = {"states": len(states), "free": len(free)}
        for name, chosen in (("random", states), ("free", free)):
            for check in ("valid", "far"):
                figures[f"{check} {name}"] = compare(
                    getattr(fast, check), getattr(reference, check), chosen
                )
        engine = fast.compiled
        engine.pairs_by_volume = engine.pairs_by_coal = 0
        for s in free:
            fast.valid(s)
        settled = engine.pairs_by_volume / max(1, engine.pairs_by_volume + engine.pairs_by_coal)
        figures["pairs settled by bounding volumes (free states)"] = settled
        figures["active pairs"] = int(fast.active.sum())
    return figures


def time_segments(
    world: armfleet.World, arms: tuple[str, ...], path: Any, totals: dict[str, Any]
) -> None:
    """Add to ``totals`` the proof of ``path`` three ways: Python, the compiled walk of the
    same steps, the compiled walk with steps sized by the distances found (the planner's)."""
    with checkers(world, arms) as (fast, reference):
        ours, theirs = PathCertifier(fast), PathCertifier(reference)
        same_walk = partial(fast.compiled.first_failure, path, False)
        verdicts = {ours.first_failure(path) is None, theirs.first_failure(path) is None}
        totals["agree"] = totals.get("agree", True) and len(verdicts) == 1 and same_walk() is None
        for name, call in (
            ("python", partial(theirs.first_failure, path)),
            ("compiled_same_steps", same_walk),
            ("compiled", partial(ours.first_failure, path)),
        ):
            totals[f"{name}_us"] = totals.get(f"{name}_us", 0.0) + best_us(call, 1)
        for name, call in (
            ("compiled_same_steps", same_walk),
            ("compiled", partial(ours.first_failure, path)),
        ):
            fast.compiled.checks = 0
            call()
            totals[f"{name}_states"] = totals.get(f"{name}_states", 0) + fast.compiled.checks
        totals["segments"] = totals.get("segments", 0) + len(path) - 1
        totals["paths"] = totals.get("paths", 0) + 1


def segment_figures(totals: dict[str, Any]) -> dict[str, Any]:
    segments = totals["segments"]
    row = {"paths": totals["paths"], "segments": segments, "agree": totals["agree"]}
    for name in ("python", "compiled_same_steps", "compiled"):
        row[f"{name}_us"] = totals[f"{name}_us"] / segments
    for name in ("compiled_same_steps", "compiled"):
        row[f"{name}_states"] = totals[f"{name}_states"] / segments
    row["ratio"] = row["python_us"] / row["compiled_us"]
    return row


@contextmanager
def python_checks() -> Iterator[None]:
    """The planner with the Python reference check (as where the kernel is not built)."""
    original = PlanningScene.checker

    def reference(self: PlanningScene, arms: Any, compiled: bool = True) -> CollisionChecker:
        return original(self, arms, compiled=False)

    PlanningScene.checker = reference  # type: ignore[method-assign]
    try:
        yield
    finally:
        PlanningScene.checker = original  # type: ignore[method-assign]


def run(count: int, seed: int) -> dict[str, Any]:
    spec = load_spec(SPEC)
    world = armfleet.launch(spec, viewer=False)
    try:
        model = CellModel(world)
        problems = ProblemSet(model, model.checker(PROBLEM_MARGIN_M), seed).problems(count)
        report: dict[str, Any] = {"states": {}}
        for arms in (("bob",), ("bob", "toby")):
            report["states"][" + ".join(arms)] = state_figures(world, arms)
        requests: dict[str, list[float]] = {"compiled": [], "python": []}
        kinds: list[str] = []
        totals: dict[str, Any] = {}
        for problem in problems:
            starts = {name: problem.q_full[list(a.q_indices)] for name, a in model.arms.items()}
            targets = {arm: problem.goal[7 * k : 7 * (k + 1)] for k, arm in enumerate(problem.arms)}
            respawn_at(world, spec, starts)
            world.plan({problem.arms[0]: world.arm(problem.arms[0]).positions})  # scene built
            times: dict[str, float] = {}
            for mode in ("compiled", "python") if problem.index % 2 else ("python", "compiled"):
                began = time.process_time()
                try:
                    if mode == "python":
                        with python_checks():
                            plan = world.plan(targets, clearance_m=CLEARANCE_M)
                    else:
                        plan = world.plan(targets, clearance_m=CLEARANCE_M)
                except armfleet.ArmfleetError:
                    times = {}
                    break
                times[mode] = (time.process_time() - began) * 1e3
                if mode == "compiled":
                    time_segments(world, tuple(problem.arms), plan.waypoints, totals)
            if times:
                kinds.append(problem.kind)
                for mode, ms in times.items():
                    requests[mode].append(ms)
        report["segments"] = segment_figures(totals)
        report["requests"] = {}
        for kind in sorted(set(kinds)):
            chosen = [k == kind for k in kinds]
            row = {}
            for mode, values in requests.items():
                picked = np.array(values)[chosen]
                row[f"{mode}_cpu_ms_median"] = float(np.median(picked))
                row[f"{mode}_cpu_ms_p95"] = float(np.percentile(picked, 95))
            row["problems"] = int(sum(chosen))
            row["ratio_median"] = row["python_cpu_ms_median"] / row["compiled_cpu_ms_median"]
            report["requests"][kind] = row
        return report
    finally:
        world.close()


def show(report: dict[str, Any]) -> None:
    for arms, figures in report["states"].items():
        print(
            f"per state, {arms} ({figures['active pairs']} active pairs, "
            f"{figures['free']}/{figures['states']} random states free):"
        )
        for name, row in figures.items():
            if isinstance(row, dict):
                print(
                    f"  {name:12s} python {row['python_us']:7.1f} us  compiled "
                    f"{row['compiled_us']:6.1f} us  x{row['ratio']:.1f}  agree {row['agree']}"
                )
        share = figures["pairs settled by bounding volumes (free states)"]
        print(f"  pairs settled by the bounding volumes (free states): {share:.1%}")
    row = report["segments"]
    print(
        f"per segment ({row['segments']} segments of {row['paths']} planned paths): python "
        f"{row['python_us']:.0f} us;  compiled, same steps {row['compiled_same_steps_us']:.0f} us "
        f"({row['compiled_same_steps_states']:.0f} states);  compiled, steps by distance "
        f"{row['compiled_us']:.0f} us ({row['compiled_states']:.0f} states)  x{row['ratio']:.1f}  "
        f"agree {row['agree']}"
    )
    for kind, row in report["requests"].items():
        print(
            f"whole request, {kind} ({row['problems']} problems): CPU ms median python "
            f"{row['python_cpu_ms_median']:.1f}  compiled {row['compiled_cpu_ms_median']:.1f}  "
            f"x{row['ratio_median']:.1f};  p95 {row['python_cpu_ms_p95']:.1f} / "
            f"{row['compiled_cpu_ms_p95']:.1f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, default=RESULTS / "collision_check.json")
    args = parser.parse_args()
    report = run(args.problems, args.seed)
    show(report)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
