"""Executed duration of planned motions: smooth (through the waypoints) against rest to rest.

The problems are benchmarks/cell_problems.py's fixed, seeded set in
launch_specs/shared_cell.yaml (the set benchmarks/planning.py plans; joint goals here).
For each problem the arms are brought up again at its start, ``world.plan`` plans it
(the planner times the path smoothly, :class:`armfleet.planning.smooth_timing.SmoothPath`,
and proves it as executed), and the same waypoints are timed rest to rest, segment by
segment (:class:`armfleet.planning.path_timing.TimedPath`, the timing before issue 27).
Both durations come from one run on the same path; nothing is executed.

It prints both durations per problem, the ratio smooth / rest-to-rest (median, worst,
best, per class) and writes benchmarks/results/motion_timing.json.

    python benchmarks/motion_timing.py --problems 20   # about a minute on 2 cores
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from armfleet.planning.scene import BULLET_MARGIN_M
from armfleet.planning.path_timing import JointLimits, TimedPath
from armfleet.spec import load_spec
from cell_execution import respawn_at  # benchmarks/ is the script's folder
from cell_model import CellModel
from cell_problems import ProblemSet

RESULTS = Path(__file__).resolve().parent / "results"
SPEC = Path(__file__).resolve().parents[1] / "launch_specs" / "shared_cell.yaml"
#: Margin of the problem set's starts and goals [m]: the planner's default clearance, plus
#: the physics' collision margin of two meshes, which the planner keeps too.
PROBLEM_MARGIN_M = 0.01 + 2 * BULLET_MARGIN_M


def limits_of(world: armfleet.World, arms: tuple[str, ...]) -> JointLimits:
    """The planned joints' limits, from each arm's position controller parameters."""
    velocity, acceleration, jerk = [], [], []
    for name in arms:
        controller = world.arm(name).position_controller
        n = controller.lower.size
        velocity.append(controller.max_velocity)
        acceleration.append(np.full(n, float(controller.parameters["max_acceleration_rad_s2"])))
        jerk.append(np.full(n, float(controller.parameters["max_jerk_rad_s3"])))
    return JointLimits(np.concatenate(velocity), np.concatenate(acceleration), np.concatenate(jerk))


def run(count: int, seed: int) -> dict[str, Any]:
    spec = load_spec(SPEC)
    world = armfleet.launch(spec, viewer=False)
    rows: list[dict[str, Any]] = []
    try:
        model = CellModel(world)
        problems = ProblemSet(model, model.checker(PROBLEM_MARGIN_M), seed).problems(count)
        for problem in problems:
            starts = {n: problem.q_full[list(a.q_indices)] for n, a in model.arms.items()}
            goals = {arm: problem.goal[7 * k : 7 * (k + 1)] for k, arm in enumerate(problem.arms)}
            row: dict[str, Any] = {"index": problem.index, "kind": problem.kind}
            rows.append(row)
            try:
                respawn_at(world, spec, starts)
                plan = world.plan(goals)
            except armfleet.ArmfleetError as exc:
                row["error"] = str(exc)
                continue
            began = time.perf_counter()
            reference = TimedPath(plan.waypoints, limits_of(world, plan.arms))
            row.update(
                waypoints=len(plan.waypoints),
                smooth_s=round(plan.timing.duration, 4),
                rest_to_rest_s=round(reference.duration, 4),
                ratio=round(plan.timing.duration / reference.duration, 4),
                smooth_timing_ms=round(plan.seconds.get("timing", 0.0) * 1e3, 2),
                rest_to_rest_timing_ms=round((time.perf_counter() - began) * 1e3, 2),
            )
    finally:
        world.close()
    timed = [r for r in rows if "ratio" in r]
    summary: dict[str, Any] = {}
    for kind in [*sorted({r["kind"] for r in timed}), "all"]:
        chosen = [r for r in timed if kind in ("all", r["kind"])]
        ratios = np.array([r["ratio"] for r in chosen])
        summary[kind] = {
            "problems": len(chosen),
            "median_ratio": round(float(np.median(ratios)), 3),
            "worst_ratio": round(float(ratios.max()), 3),
            "best_ratio": round(float(ratios.min()), 3),
            "median_smooth_s": round(float(np.median([r["smooth_s"] for r in chosen])), 3),
            "median_rest_to_rest_s": round(
                float(np.median([r["rest_to_rest_s"] for r in chosen])), 3
            ),
            "median_smooth_timing_ms": round(
                float(np.median([r["smooth_timing_ms"] for r in chosen])), 2
            ),
        }
    return {"settings": {"problems": count, "seed": seed}, "summary": summary, "problems": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problems", type=int, default=20, help="problems (default 20)")
    parser.add_argument("--seed", type=int, default=16)
    parser.add_argument("--json", type=Path, default=RESULTS / "motion_timing.json")
    args = parser.parse_args()
    figures = run(args.problems, args.seed)
    print(f"{'#':>3} {'kind':7} {'wp':>3} {'rest-to-rest s':>14} {'smooth s':>9} {'ratio':>6}")
    for row in figures["problems"]:
        if "ratio" not in row:
            print(f"{row['index']:>3} {row['kind']:7} not planned: {row['error']}")
            continue
        print(
            f"{row['index']:>3} {row['kind']:7} {row['waypoints']:>3} "
            f"{row['rest_to_rest_s']:>14.3f} {row['smooth_s']:>9.3f} {row['ratio']:>6.3f}"
        )
    for kind, figures_of in figures["summary"].items():
        print(
            f"{kind:7}: {figures_of['problems']} problems, smooth / rest-to-rest median "
            f"{figures_of['median_ratio']:.3f} (worst {figures_of['worst_ratio']:.3f}, best "
            f"{figures_of['best_ratio']:.3f}); timing {figures_of['median_smooth_timing_ms']} ms"
        )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(figures, indent=1))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
