"""Where a world step goes: World.step's phases timed one by one, per arm.

It runs N Pandas on the fleet benchmark's grid following random targets (as
benchmarks/fleet.py does) and times each phase of ``World.step`` separately: the
controllers (broadcasters, position controllers, grippers), writing the torques,
the physics step, reading the joints, objects, contacts, the safety supervisor and
the rest (requests, status). It mirrors ``World.step`` line by line, so it reaches
into the world's parts; keep the two in step when either changes.

    python benchmarks/step_phases.py              # 30 arms
    python benchmarks/step_phases.py --arms 1 --compiled-control off
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import pybullet as p

from fleet import GRID_COLUMNS, random_targets  # benchmarks/ is the script's folder

RESULTS = Path(__file__).resolve().parent / "results"
PHASES = ("controllers", "write", "physics", "read", "objects", "contacts", "safety", "other")


def phase_times(arms: int, compiled: bool, repeats: int, steps: int) -> dict[str, float]:
    """Mean microseconds per step of each phase (the first repeat is a warm-up)."""
    world = armfleet.World(compiled_control=compiled)
    for i in range(arms):
        world.spawn(f"arm{i}", at=(float(i // GRID_COLUMNS), float(i % GRID_COLUMNS)))
    world.run(0.05)
    rng = np.random.default_rng(1)
    totals = dict.fromkeys(PHASES, 0.0)
    counted = 0
    w = world  # the private parts World.step uses, in its order
    for repeat in range(repeats + 1):
        random_targets(world, rng)
        for _ in range(steps):
            t0 = time.perf_counter()
            w._requests.drain()
            w._guard.begin_step()
            stamp = w.time
            t1 = time.perf_counter()
            w._controllers.update(stamp, w._step_index)
            t2 = time.perf_counter()
            w._memory.write()
            t3 = time.perf_counter()
            p.stepSimulation(physicsClientId=w._client)
            w._step_index += 1
            t4 = time.perf_counter()
            w._memory.read()
            t5 = time.perf_counter()
            w._objects.after_step(w.time)
            t6 = time.perf_counter()
            w._contacts.scan(w.time)
            t7 = time.perf_counter()
            w._safety.after_scan()
            t8 = time.perf_counter()
            if w._step_index % w._status_period_steps == 0:
                for arm in w._arms.values():
                    w._publish_status(arm)
            w._guard.end_step()
            t9 = time.perf_counter()
            if repeat == 0:
                continue
            marks = (t1, t2, t3, t4, t5, t6, t7, t8)
            for name, start, end in zip(PHASES[:-1], marks, marks[1:], strict=False):
                totals[name] += end - start
            totals["other"] += (t1 - t0) + (t9 - t8)
            counted += 1
    world.close()
    return {name: round(total / counted * 1e6, 1) for name, total in totals.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", type=int, default=30)
    parser.add_argument("--compiled-control", choices=("on", "off"), default="on")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--json", type=Path, default=RESULTS / "step_phases.json")
    args = parser.parse_args()
    compiled = args.compiled_control == "on"
    load = os.getloadavg()[0]
    phases = phase_times(args.arms, compiled, args.repeats, args.steps)
    total = sum(phases.values())
    print(f"{args.arms} Pandas, compiled control {args.compiled_control}, load {load:.2f}")
    print(f"{'phase':<12} {'us/step':>8} {'us/arm':>7}")
    for name, value in phases.items():
        print(f"{name:<12} {value:>8.1f} {value / args.arms:>7.2f}")
    print(f"{'total':<12} {total:>8.1f} {total / args.arms:>7.2f}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    result = {"arms": args.arms, "compiled_control": compiled, "load": load, "phases_us": phases}
    args.json.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
