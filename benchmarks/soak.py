"""Soak: many arms, random reachable targets, contacts on, for a long simulated time.

Checks that nothing degrades: no NaN, no exception, memory flat after warm-up,
every arm still tracking at the end. Prints a summary and writes JSON.

    python benchmarks/soak.py              # 30 arms, 600 s simulated (~20-30 min)
    python benchmarks/soak.py --short      # 4 arms, 10 s simulated (CI)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import time
from pathlib import Path

import numpy as np

import armfleet
from armfleet.messages import ArmMode, JointState
from armfleet.spec import FleetSpec, load_spec

RESULTS = Path(__file__).resolve().parent / "results"
COMMAND_PERIOD_S = 0.5
TRACKING_BOUND_RAD = 1e-3


def rss_mb() -> float:
    """Resident set size of this process now [MB] (Linux)."""
    with open("/proc/self/statm") as statm:
        pages = int(statm.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def soak(spec: FleetSpec, duration_s: float, seed: int) -> dict[str, object]:
    rng = np.random.default_rng(seed)
    started = time.perf_counter()
    world = armfleet.launch(spec, viewer=False)
    bringup_s = time.perf_counter() - started
    non_finite = 0

    def check(state: JointState) -> None:
        nonlocal non_finite
        if not (np.isfinite(state.position).all() and np.isfinite(state.velocity).all()):
            non_finite += 1

    for name in world.arms:
        world.bus.subscribe(f"/{name}/joint_states", check)
    homes = {name: np.array(arm.description.home) for name, arm in world.arms.items()}
    resets = refused = 0
    warm_rss = rss_mb()
    warm_up_s = min(30.0, duration_s / 5)
    wall_start = time.perf_counter()
    try:
        while world.time < duration_s:
            for name, arm in world.arms.items():
                mode = arm.status(world.time).mode
                if mode is ArmMode.ERROR or (mode is ArmMode.PROTECTIVE_STOP and not arm.is_moving):
                    arm.reset()
                    resets += 1
                    try:
                        arm.move_to(homes[name])
                    except armfleet.ArmfleetError:
                        refused += 1
                elif mode is ArmMode.HOLDING:
                    lower, upper = arm.joint_limits
                    try:
                        arm.move_to(lower + (upper - lower) * rng.uniform(0.2, 0.8, lower.size))
                    except armfleet.ArmfleetError:
                        refused += 1
            world.run(COMMAND_PERIOD_S)
            if world.time <= warm_up_s:
                warm_rss = rss_mb()
        # The end: every arm goes home, one retry after another (arms touching on the
        # way stop, are reset and sent again), then must be tracking its reference.
        deadline = world.time + 30.0
        while world.time < deadline:
            away = [
                name
                for name, arm in world.arms.items()
                if float(np.abs(arm.positions - homes[name]).max()) > TRACKING_BOUND_RAD
            ]
            if not away:
                break
            for name in away:
                arm = world.arm(name)
                if not arm.is_moving:
                    arm.reset()
                    with contextlib.suppress(armfleet.ArmfleetError):
                        arm.move_to(homes[name])
            world.run(0.5)
        final_errors = {
            name: float(np.abs(arm.positions - homes[name]).max())
            for name, arm in world.arms.items()
        }
        tracking_errors = {
            name: arm.position_controller.tracking_error for name, arm in world.arms.items()
        }
        faulted = [name for name, arm in world.arms.items() if arm.controller_manager.fault]
        wall_s = time.perf_counter() - wall_start
        end_rss = rss_mb()
        return {
            "arms": len(world.arms),
            "simulated_s": round(world.time, 3),
            "wall_s": round(wall_s, 2),
            "bringup_s": round(bringup_s, 3),
            "rss_warm_mb": round(warm_rss, 1),
            "rss_end_mb": round(end_rss, 1),
            "rss_growth_pct": round(100 * (end_rss - warm_rss) / warm_rss, 2),
            "contacts": world.contacts.total_contacts,
            "protective_stops": world_stops(world),
            "resets": resets,
            "refused_targets": refused,
            "non_finite_states": non_finite,
            "arms_home": sum(e < TRACKING_BOUND_RAD for e in final_errors.values()),
            "worst_distance_from_home_rad": max(final_errors.values()),
            "worst_tracking_error_rad": max(tracking_errors.values()),
            "arms_in_error": len(faulted),
            "all_tracking": not faulted
            and all(e < TRACKING_BOUND_RAD for e in tracking_errors.values())
            and all(e < TRACKING_BOUND_RAD for e in final_errors.values()),
        }
    finally:
        world.close()


def world_stops(world: armfleet.World) -> int:
    return world.safety.stops


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="4 arms, 10 s (CI)")
    parser.add_argument("--duration", type=float, default=None, help="simulated seconds")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", type=Path, default=RESULTS / "soak.json")
    args = parser.parse_args()
    if args.short:
        spec = load_spec("grid_30")
        spec = FleetSpec(spec.world, spec.arms[:2] + spec.arms[6:8], spec.source)
        duration = args.duration or 10.0
    else:
        spec, duration = load_spec("grid_30"), args.duration or 600.0
    result = soak(spec, duration, args.seed)
    for key, value in result.items():
        print(f"{key:>24}: {value}")
    ok = (
        result["non_finite_states"] == 0
        and result["all_tracking"]
        and math.isfinite(float(str(result["rss_growth_pct"])))
        and float(str(result["rss_growth_pct"])) < 5.0
    )
    print("soak:", "ok" if ok else "FAILED")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2))
    raise SystemExit(0 if ok else 1)


if __name__ == "__main__":
    main()
