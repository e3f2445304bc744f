"""Environment overhead benchmark: what ``MultiArmEnv.step`` costs on top of the world it steps.

For 1, 2 and 4 Pandas (``armfleet/Reach-v0``'s row, 1 m apart) and control periods of 1,
10 and 50 physics steps it measures, in turns so that a drift of the machine hits both:
  env - ``env.step(action)``: check every arm's action, send each arm a new joint target
        (a Ruckig replan), run the control period, observe (joints, tool0 from TF,
        gripper, target) and reward. The actions are joint positions sweeping each joint
        +-0.2 rad around its start, so every step sends every arm a new target and no arm
        ever touches anything;
  raw - ``world.step()`` in a loop on the same world, as many physics steps, the arms
        holding (nothing sent, nothing observed);
  cmd - the same loop sending each arm the env's joint targets with ``arm.move_to`` every
        control period: the arms move as in ``env``, without the environment around them
        (no checks, observations or reward).
It prints environment steps per second, physics steps per second all three ways, the
ratios env/raw (what an environment step costs over a bare physics loop: 1.0 is nothing)
and env/cmd (the environment's own share), and the environment's own cost per step; and
writes benchmarks/results/env_overhead.json. Resets are not timed here: benchmarks/envs.py
times them, and steps, beside panda-gym's.

    python benchmarks/env_overhead.py            # 3 sizes x 3 periods, 5 turns (about 90 s)
    python benchmarks/env_overhead.py --short    # 2 arms, periods 1 and 10, 1 turn (CI)
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from armfleet.envs import ReachEnv

RESULTS = Path(__file__).resolve().parent / "results"
#: Joint-position sweep of the actions: amplitude [rad] and period [s].
SWEEP_RAD, SWEEP_PERIOD_S = 0.2, 2.0


def actions(env: ReachEnv, count: int) -> list[dict[str, Any]]:
    """``count`` joint-position actions, one per environment step, made before timing."""
    start = {name: env.world.arm(name).positions for name in env.arm_names}
    phases = np.linspace(0.0, np.pi, 7)
    made = []
    for index in range(count):
        angle = 2 * np.pi * index * env.step_s / SWEEP_PERIOD_S
        action = {}
        for name, q in start.items():
            entry = {"joint_positions": (q + SWEEP_RAD * np.sin(angle + phases)).astype(np.float32)}
            if "gripper" in env.arm_action_space(name).spaces:
                entry["gripper"] = np.zeros(1, np.float32)
            action[name] = entry
        made.append(action)
    return made


def timed_env(env: ReachEnv, steps: int) -> float:
    """Wall time of ``steps`` environment steps from a fresh episode [s]."""
    env.reset(seed=0)
    planned = actions(env, steps)
    began = time.perf_counter()
    for action in planned:
        _, _, terminated, _, info = env.step(action)
        if terminated or info["refused"]:
            raise RuntimeError(f"the benchmark's motion was stopped or refused: {info}")
    return time.perf_counter() - began


def timed_raw(env: ReachEnv, physics_steps: int) -> float:
    """Wall time of ``physics_steps`` of ``world.step()`` on a fresh episode's world [s]."""
    env.reset(seed=0)
    world = env.world
    began = time.perf_counter()
    for _ in range(physics_steps):
        world.step()
    return time.perf_counter() - began


def timed_commands(env: ReachEnv, steps: int) -> float:
    """Wall time of ``steps`` control periods of ``world.step()``, each arm sent the
    benchmark's joint target with ``arm.move_to`` at the start of each period [s]."""
    env.reset(seed=0)
    world = env.world
    arms = [world.arm(name) for name in env.arm_names]
    planned = [
        [action[arm.name]["joint_positions"].astype(float) for arm in arms]
        for action in actions(env, steps)
    ]
    began = time.perf_counter()
    for targets in planned:
        for arm, target in zip(arms, targets, strict=True):
            arm.move_to(target)
        for _ in range(env.control_period):
            world.step()
    return time.perf_counter() - began


def measure(arms: int, period: int, env_steps: int, turns: int) -> dict[str, Any]:
    env = ReachEnv(arm_count=arms, control_period=period, action_kind="joint_positions")
    physics = env_steps * period
    env_s, raw_s, cmd_s = [], [], []
    for _ in range(turns):
        env_s.append(timed_env(env, env_steps))
        raw_s.append(timed_raw(env, physics))
        cmd_s.append(timed_commands(env, env_steps))
    env.close()
    env_time, raw_time = statistics.median(env_s), statistics.median(raw_s)
    cmd_time = statistics.median(cmd_s)
    return {
        "arms": arms,
        "control_period": period,
        "env_steps": env_steps,
        "physics_steps": physics,
        "env_s": env_s,
        "raw_s": raw_s,
        "cmd_s": cmd_s,
        "env_steps_per_s": env_steps / env_time,
        "env_physics_steps_per_s": physics / env_time,
        "raw_physics_steps_per_s": physics / raw_time,
        "cmd_physics_steps_per_s": physics / cmd_time,
        "env_over_raw": env_time / raw_time,
        "env_over_cmd": env_time / cmd_time,
        "env_own_ms_per_step": (env_time - cmd_time) / env_steps * 1e3,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="2 arms, periods 1 and 10 (CI)")
    parser.add_argument(
        "--physics-steps", type=int, default=2000, help="physics steps per measurement (min.)"
    )
    parser.add_argument("--turns", type=int, default=5, help="turns of env and raw (medians)")
    parser.add_argument("--json", type=Path, default=RESULTS / "env_overhead.json")
    args = parser.parse_args()
    sizes, periods, turns, physics = (
        ((2,), (1, 10), 1, 200) if args.short else ((1, 2, 4), (1, 10, 50), args.turns,
                                                    args.physics_steps)
    )  # fmt: skip
    load = os.getloadavg()[0]
    rows = []
    for arms in sizes:
        for period in periods:
            env_steps = max(20, physics // period)
            rows.append(measure(arms, period, env_steps, turns))
            print(f"measured {arms} arm(s), period {period}", file=sys.stderr, flush=True)
    print(f"machine load (1 min) before: {load:.2f}, after: {os.getloadavg()[0]:.2f}")
    print(
        f"{'arms':>4} {'period':>6} {'env steps/s':>12} {'env phys/s':>11} "
        f"{'cmd phys/s':>11} {'raw phys/s':>11} {'env/raw':>8} {'env/cmd':>8} "
        f"{'env own ms/step':>16}"
    )
    for row in rows:
        print(
            f"{row['arms']:>4} {row['control_period']:>6} {row['env_steps_per_s']:>12.0f} "
            f"{row['env_physics_steps_per_s']:>11.0f} {row['cmd_physics_steps_per_s']:>11.0f} "
            f"{row['raw_physics_steps_per_s']:>11.0f} {row['env_over_raw']:>8.2f} "
            f"{row['env_over_cmd']:>8.2f} {row['env_own_ms_per_step']:>16.3f}"
        )
    result = {
        "load_before": load,
        "load_after": os.getloadavg()[0],
        "cores": os.cpu_count(),
        "python": sys.version.split()[0],
        "turns": turns,
        "rows": rows,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
