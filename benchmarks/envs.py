"""Environment benchmark: CPU time of a reset and of a step, armfleet beside panda-gym.

Side by side in one process, in turns (so that a drift of the machine hits all four):
  reach    - ``armfleet/Reach-v0`` with one Panda (``ReachEnv(arm_count=1)``), joint-delta
             actions, 20 physics steps of 1 ms per environment step;
  servo    - the same in the form SAC learns (benchmarks/learning.py): ``tool_servo``
             actions (IK each step, the responsive controller), ``near`` targets;
  handover - ``armfleet/Handover-v0`` (bob, toby, two tables, the bar, the mat), tool-delta
             actions with IK, 20 physics steps of 1 ms;
  panda    - panda-gym's ``PandaReach-v3`` (one Panda, end-effector deltas with IK), 20
             physics steps of 2 ms (its registered setting: a 40 ms control period).
Each reset follows a few steps of an episode (not timed), as in training; every step's
action is sampled beforehand; an episode that ends is reset without being timed. CPU time
is ``time.process_time`` around each call (the process's own, whatever else the machine
runs). It prints medians and 95th percentiles per reset and per step [ms], the ratios to
panda-gym's, and writes benchmarks/results/envs.json. A third figure, ``physics``, is the
CPU time of the same number of bare ``stepSimulation`` calls on each environment's own
PyBullet world right after a reset: the share of a step no environment code can cut; and,
for armfleet's, ``world``: a control period of ``world.step()`` right after a reset
(controllers, physics, contacts and topics, no command sent), so that a step's median less
it is what the environment and the arms' commands add.

panda-gym is not a dependency of armfleet: install the benchmark's extra first,

    pip install -e '.[envs-bench]'       # panda-gym>=3.0.7
    python benchmarks/envs.py            # 200 resets and 2000 steps each (about 1 min)
    python benchmarks/envs.py --short    # 20 and 200 (CI)

What an environment step costs on top of the bare physics loop is
benchmarks/env_overhead.py's.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pybullet as p

from armfleet.envs import HandoverEnv, ReachEnv

RESULTS = Path(__file__).resolve().parent / "results"
#: Untimed steps before each timed reset.
STEPS_BEFORE_RESET = 5
#: Turns the resets and steps are split into (all environments in each turn).
TURNS = 4


def panda_reach() -> gym.Env[Any, Any]:
    """panda-gym's PandaReach-v3, or one line saying how to get it."""
    try:
        import panda_gym  # noqa: F401 - registers its environments
    except ImportError:
        sys.exit("panda-gym is not installed: pip install -e '.[envs-bench]' (panda-gym>=3.0.7)")
    return gym.make("PandaReach-v3")


MAKERS: dict[str, Callable[[], gym.Env[Any, Any]]] = {
    "reach": lambda: ReachEnv(arm_count=1),
    "servo": lambda: ReachEnv(arm_count=1, action_kind="tool_servo", target_region="near"),
    "handover": HandoverEnv,
    "panda": panda_reach,
}


def timed_resets(env: gym.Env[Any, Any], count: int, seed: int) -> list[float]:
    """CPU time of ``count`` resets, each after a few steps [s]."""
    times = []
    for index in range(count):
        for _ in range(STEPS_BEFORE_RESET):
            env.step(env.action_space.sample())
        began = time.process_time()
        env.reset(seed=seed + index)
        times.append(time.process_time() - began)
    return times


def timed_steps(env: gym.Env[Any, Any], count: int, seed: int) -> list[float]:
    """CPU time of ``count`` steps of sampled actions [s]; ended episodes reset untimed."""
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(count)]
    env.reset(seed=seed)
    times = []
    for action in actions:
        began = time.process_time()
        _, _, terminated, truncated, _ = env.step(action)
        times.append(time.process_time() - began)
        if terminated or truncated:
            env.reset()
    return times


def physics_client(env: gym.Env[Any, Any]) -> tuple[Callable[[], None], int]:
    """A function doing one bare PyBullet step of ``env``'s world, and the steps per
    environment step."""
    unwrapped: Any = env.unwrapped
    if hasattr(unwrapped, "world"):
        client = unwrapped.world.physics_client
        return lambda: p.stepSimulation(physicsClientId=client), unwrapped.control_period
    sim = unwrapped.sim  # panda-gym
    return sim.physics_client.stepSimulation, sim.n_substeps


def timed_physics(env: gym.Env[Any, Any], count: int, seed: int) -> list[float]:
    """CPU time of the bare PyBullet steps of ``count`` environment steps, each right
    after a reset (no controller, no observation: the physics' share of a step) [s]."""
    step, substeps = physics_client(env)
    times = []
    for index in range(count):
        env.reset(seed=seed + index)
        began = time.process_time()
        for _ in range(substeps):
            step()
        times.append(time.process_time() - began)
    return times


def timed_world(env: gym.Env[Any, Any], count: int, seed: int) -> list[float]:
    """armfleet only: CPU time of a control period of ``world.step()`` (controllers,
    physics, contacts, topics; the arms holding after a reset, no command sent) [s]."""
    unwrapped: Any = env.unwrapped
    if not hasattr(unwrapped, "world"):
        return []
    times = []
    for index in range(count):
        env.reset(seed=seed + index)
        world = unwrapped.world
        began = time.process_time()
        for _ in range(unwrapped.control_period):
            world.step()
        times.append(time.process_time() - began)
    return times


def summary(times: list[float]) -> dict[str, Any]:
    if not times:
        return {}
    ms = np.array(times) * 1e3
    return {
        "median_ms": float(statistics.median(ms)),
        "p95_ms": float(np.percentile(ms, 95)),
        "mean_ms": float(ms.mean()),
        "count": len(times),
    }


def control_period_s(env: gym.Env[Any, Any]) -> float:
    unwrapped: Any = env.unwrapped
    if hasattr(unwrapped, "step_s"):
        return float(unwrapped.step_s)
    return float(unwrapped.sim.dt)  # panda-gym: n_substeps x timestep


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="20 resets and 200 steps (CI)")
    parser.add_argument("--resets", type=int, default=200)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--json", type=Path, default=RESULTS / "envs.json")
    args = parser.parse_args()
    resets, steps = (20, 200) if args.short else (args.resets, args.steps)
    load = os.getloadavg()[0]
    envs = {name: make() for name, make in MAKERS.items()}
    for env in envs.values():
        env.reset(seed=0)
    reset_s: dict[str, list[float]] = {name: [] for name in envs}
    step_s: dict[str, list[float]] = {name: [] for name in envs}
    physics_s: dict[str, list[float]] = {name: [] for name in envs}
    world_s: dict[str, list[float]] = {name: [] for name in envs}
    for turn in range(TURNS):
        for name, env in envs.items():
            reset_s[name] += timed_resets(env, resets // TURNS, seed=1000 * turn)
            step_s[name] += timed_steps(env, steps // TURNS, seed=turn)
            physics_s[name] += timed_physics(env, resets // TURNS, seed=1000 * turn)
            world_s[name] += timed_world(env, resets // TURNS, seed=1000 * turn)
        print(f"turn {turn + 1} of {TURNS} done", file=sys.stderr, flush=True)
    rows: dict[str, dict[str, Any]] = {
        name: {
            "control_period_s": control_period_s(env),
            "reset": summary(reset_s[name]),
            "step": summary(step_s[name]),
            "physics": summary(physics_s[name]),
            "world": summary(world_s[name]),
        }
        for name, env in envs.items()
    }
    for env in envs.values():
        env.close()
    panda = rows["panda"]
    for row in rows.values():
        for kind in ("reset", "step", "physics"):
            row[kind]["median_over_panda"] = row[kind]["median_ms"] / panda[kind]["median_ms"]
    print(f"machine load (1 min) before: {load:.2f}, after: {os.getloadavg()[0]:.2f}")
    print(
        f"{'env':<10} {'period ms':>9} {'reset med':>10} {'reset p95':>10} {'x panda':>8} "
        f"{'step med':>9} {'step p95':>9} {'x panda':>8} {'physics':>8} {'x panda':>8} "
        f"{'world':>8}   (CPU ms)"
    )
    for name, row in rows.items():
        reset, step, physics = row["reset"], row["step"], row["physics"]
        world = f"{row['world']['median_ms']:>8.3f}" if row["world"] else f"{'-':>8}"
        print(
            f"{name:<10} {row['control_period_s'] * 1e3:>9.0f} {reset['median_ms']:>10.3f} "
            f"{reset['p95_ms']:>10.3f} {reset['median_over_panda']:>8.2f} "
            f"{step['median_ms']:>9.3f} {step['p95_ms']:>9.3f} {step['median_over_panda']:>8.2f} "
            f"{physics['median_ms']:>8.3f} {physics['median_over_panda']:>8.2f} {world}"
        )
    result = {
        "load_before": load,
        "load_after": os.getloadavg()[0],
        "cores": os.cpu_count(),
        "python": sys.version.split()[0],
        "resets": resets,
        "steps": steps,
        "rows": rows,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
