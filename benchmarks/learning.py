"""Learning baseline: Stable-Baselines3's SAC on ``armfleet/Reach-v0`` with one Panda.

What a user needs to tell "too few steps" from "a broken task": SAC trains on the flat
form of the environment, no wrapper of one's own:
``gym.make("armfleet/Reach-v0", flat=True, action_kind="tool_servo", target_region="near",
max_episode_steps=50)``: one Panda; actions in [-1, 1], tool0 moved up to 2 cm along x, y
and z from where it is (its orientation held), on the responsive controller that comes
with ``tool_servo``; a target in a 0.3 m cube around tool0's start, reached within 2 cm
(Reach's tolerance), 50 steps of 20 ms per episode; the shipped reward (minus the
tool0-target distance every step, +1 on success, a stop penalty; docs/envs.md).
``--action-kind`` and ``--target-region`` train on Reach's other forms, for comparison
(``tool_delta`` with 5 mm steps: :data:`TOOL_STEP_M`; ``workspace`` targets: 200 steps).
Every ``--eval-every`` steps the deterministic policy runs
``--curve-episodes`` seeded episodes (seeds 10_000, 10_001, ...: never trained on) and
their success rate is a point of the learning curve; at the end it runs
``--final-episodes`` (100) seeded episodes. It writes the curve as a PNG
(docs/images/reach-learning.png) and the figures as JSON
(benchmarks/results/learning.json), and prints the success reached and the time taken.

    nice python benchmarks/learning.py                  # 30,000 steps (~10 min)
    python benchmarks/learning.py --steps 2000 --short  # a smoke run (no PNG, no JSON)

Needs the ``rl`` extra (``pip install 'armfleet[rl]'``) and matplotlib (``plot``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import armfleet.envs
from armfleet.envs import REACH_ID

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
FIGURE = ROOT / "docs" / "images" / "reach-learning.png"
#: Evaluation episodes are seeded from here on (training episodes draw from seed 0's stream).
EVAL_SEED = 10_000
#: Episode length of the baseline [steps]: 1 s at the 20 ms control period (panda-gym's
#: PandaReach: 50 steps of 40 ms).
EPISODE_STEPS = 50
#: Largest move and turn of tool0 per step with ``tool_delta`` actions [m, rad] (only for
#: the comparison runs with ``--action-kind tool_delta``).
TOOL_STEP_M, TOOL_TURN_RAD = 0.005, 1e-4


def make_env(action_kind: str, target_region: str = "near") -> gym.Env[Any, Any]:
    """Reach with one Panda, flat. ``tool_servo`` (the default): tool0 moved up to 2 cm
    along x, y and z from where it is, targets ``"near"``, :data:`EPISODE_STEPS` steps;
    ``tool_delta``: moves of the previous target of at most :data:`TOOL_STEP_M`."""
    options: dict[str, Any] = {"target_region": target_region}
    if target_region == "near":
        options["max_episode_steps"] = EPISODE_STEPS
    if action_kind == "tool_delta":
        options.update(max_tool_step_m=TOOL_STEP_M, max_tool_step_rad=TOOL_TURN_RAD)
    return gym.make(REACH_ID, flat=True, action_kind=action_kind, **options)


def evaluate(
    model: Any, episodes: int, action_kind: str, target_region: str
) -> tuple[float, float, float]:
    """The deterministic policy's success rate over ``episodes`` seeded episodes, their
    mean length [steps] and their mean final tool0-target distance [m]."""
    env = make_env(action_kind, target_region)
    successes, lengths, distances = 0, [], []
    try:
        for index in range(episodes):
            observation, _ = env.reset(seed=EVAL_SEED + index)
            for step in range(1, 10_000):
                action, _ = model.predict(observation, deterministic=True)
                observation, _, terminated, truncated, info = env.step(action)
                if terminated or truncated:
                    successes += bool(info["success"])
                    lengths.append(step)
                    distances.append(info["distance_m"]["arm0"])
                    break
    finally:
        env.close()
    return successes / episodes, float(np.mean(lengths)), float(np.mean(distances))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=30_000, help="training steps")
    parser.add_argument("--eval-every", type=int, default=2_500, help="steps between curve points")
    parser.add_argument("--curve-episodes", type=int, default=20, help="episodes per point")
    parser.add_argument("--final-episodes", type=int, default=100, help="episodes at the end")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--action-kind", default="tool_servo", choices=["tool_servo", "tool_delta", "joint_deltas"],
        help="tool_servo (default): tool0 moved from where it is; the others: for comparison",
    )  # fmt: skip
    parser.add_argument(
        "--target-region", default="near", choices=["near", "workspace"],
        help="near (default): a 0.3 m cube around tool0's start; workspace: Reach's default",
    )  # fmt: skip
    parser.add_argument("--short", action="store_true", help="write no PNG and no JSON")
    args = parser.parse_args()

    import torch
    from stable_baselines3 import SAC
    from stable_baselines3.common.callbacks import BaseCallback

    torch.set_num_threads(1)  # a small network: one thread is the fastest on a shared machine
    del armfleet.envs  # imported to register the ids
    env = make_env(args.action_kind, args.target_region)
    model = SAC(
        "MlpPolicy",
        env,
        learning_rate=1e-3,
        buffer_size=200_000,
        learning_starts=1_000,
        batch_size=128,
        gamma=0.95,
        tau=0.05,
        policy_kwargs={"net_arch": [128, 128]},
        seed=args.seed,
        verbose=0,
    )
    curve: list[dict[str, float]] = []
    started = time.perf_counter()

    class Curve(BaseCallback):
        def _on_step(self) -> bool:
            if self.num_timesteps % args.eval_every == 0:
                success, length, distance = evaluate(
                    model, args.curve_episodes, args.action_kind, args.target_region
                )
                elapsed = time.perf_counter() - started
                point = {"steps": self.num_timesteps, "success": success, "distance_m": distance}
                curve.append({**point, "s": elapsed})
                print(
                    f"{self.num_timesteps:>7} steps  success {success:6.1%}  "
                    f"mean length {length:5.1f}  final distance {distance:.3f} m  "
                    f"{elapsed:6.0f} s",
                    flush=True,
                )
            return True

    model.learn(total_timesteps=args.steps, callback=Curve())
    trained_s = time.perf_counter() - started
    success, length, distance = evaluate(
        model, args.final_episodes, args.action_kind, args.target_region
    )
    total_s = time.perf_counter() - started
    env.close()
    print(
        f"SAC on {REACH_ID}, one Panda: {args.steps} steps in {trained_s:.0f} s; "
        f"success on {args.final_episodes} seeded episodes: {success:.1%} "
        f"(mean length {length:.1f} steps, final distance {distance:.3f} m); "
        f"total {total_s:.0f} s"
    )
    if args.short:
        return 0
    figures = {
        "env": REACH_ID,
        "algorithm": "SAC",
        "action_kind": args.action_kind,
        "target_region": args.target_region,
        "command": " ".join(["python", "benchmarks/learning.py", *sys.argv[1:]]),
        "steps": args.steps,
        "train_s": trained_s,
        "total_s": total_s,
        "final_episodes": args.final_episodes,
        "final_success": success,
        "final_mean_length": length,
        "final_mean_distance_m": distance,
        "curve": curve,
        "load_average": os.getloadavg()[0],
        "python": sys.version.split()[0],
    }
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "learning.json").write_text(json.dumps(figures, indent=1) + "\n")
    plot(curve, success, args)
    print(f"wrote {FIGURE.relative_to(ROOT)} and {(RESULTS / 'learning.json').relative_to(ROOT)}")
    return 0


def plot(curve: list[dict[str, float]], final: float, args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 3.6), dpi=120)
    axes.plot(
        [p["steps"] for p in curve],
        [100 * p["success"] for p in curve],
        marker="o",
        label=f"{args.curve_episodes} seeded episodes",
    )
    axes.scatter(
        [args.steps], [100 * final], color="black", zorder=3,
        label=f"final: {final:.0%} of {args.final_episodes}",
    )  # fmt: skip
    axes.axhline(90, color="grey", linestyle=":", linewidth=1)
    axes.set_xlabel("training steps (20 ms each)")
    axes.set_ylabel("success [%]")
    axes.set_ylim(-3, 103)
    axes.set_title("SAC on armfleet/Reach-v0, one Panda (benchmarks/learning.py)")
    axes.legend(loc="lower right")
    axes.grid(alpha=0.3)
    figure.tight_layout()
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(FIGURE)


if __name__ == "__main__":
    sys.exit(main())
