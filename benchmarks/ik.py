"""IK benchmark: success rate and time per solve of armfleet's inverse kinematics, per model.

For every model in description/ it spawns one arm at home and asks for N poses
of tool0: forward kinematics of configurations drawn uniformly within the joint
limits (reachable by construction, anywhere in the workspace, so often far from
home). Each solve is seeded from home, as ``arm.solve_ik`` seeds from the
measured state. A solve succeeds when it converges and the forward kinematics of
its answer is within 1e-4 m / 1e-4 rad of the pose. It prints, per model, the
success rate, the median and p95 wall time per solve, and how often the random
restarts were needed; and writes benchmarks/results/ik.json.

    python benchmarks/ik.py            # N = 500 per model
    python benchmarks/ik.py --short    # N = 10 per model (CI)
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import json
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from armfleet.description import ModelLibrary

RESULTS = Path(__file__).resolve().parent / "results"
CHECK_M, CHECK_RAD = 1e-4, 1e-4


def bench_model(model: str, poses: int, seed: int) -> dict[str, Any]:
    """Solve ``poses`` random reachable tool0 poses of ``model`` from home."""
    rng = np.random.default_rng(seed)
    with armfleet.World() as world:
        arm = world.spawn("bob", model=model)
        tool = arm.description.tool0
        home = arm.body.position.copy()
        joints = int(arm.kinematics.arm_indices.size)
        lower, upper = arm.joint_limits
        times_s, iterations, successes, restarted = [], [], 0, 0
        for _ in range(poses):
            q = home.copy()
            q[arm.kinematics.arm_indices] = rng.uniform(lower, upper)
            goal = arm.ik.frame_pose(tool, q)
            started = time.perf_counter()
            solution = arm.ik.solve(tool, goal, home)
            times_s.append(time.perf_counter() - started)
            error = goal.actInv(arm.ik.frame_pose(tool, solution.positions))
            within = (
                np.linalg.norm(error.translation) <= CHECK_M
                and np.linalg.norm(pin.log3(error.rotation)) <= CHECK_RAD
            )
            successes += bool(solution.converged and within)
            restarted += solution.restarts > 0
            iterations.append(solution.iterations)
    ms = np.array(times_s) * 1e3
    return {
        "model": model,
        "joints": joints,
        "poses": poses,
        "success_rate": successes / poses,
        "restarted_fraction": restarted / poses,
        "median_ms": float(np.median(ms)),
        "p95_ms": float(np.percentile(ms, 95)),
        "max_ms": float(ms.max()),
        "median_iterations": float(np.median(iterations)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="N = 10 per model (CI)")
    parser.add_argument("--poses", type=int, default=500, help="poses per model")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", type=Path, default=RESULTS / "ik.json")
    args = parser.parse_args()
    poses = 10 if args.short else args.poses
    rows = [bench_model(model, poses, args.seed) for model in ModelLibrary().names]
    print(f"IK of tool0, {poses} random reachable poses per model, seeded from home")
    print(f"{'model':8} {'joints':>6} {'success':>8} {'restarts':>9} {'median':>9} {'p95':>9}")
    for row in rows:
        print(
            f"{row['model']:8} {row['joints']:6d} {row['success_rate']:8.1%} "
            f"{row['restarted_fraction']:9.1%} {row['median_ms']:7.2f}ms {row['p95_ms']:7.2f}ms"
        )
    result = {
        "poses_per_model": poses,
        "seed": args.seed,
        "check_m": CHECK_M,
        "check_rad": CHECK_RAD,
        "python": platform.python_version(),
        "models": rows,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
