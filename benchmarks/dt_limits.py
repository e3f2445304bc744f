"""Which physics steps every shipped model works at: the measurement behind
``armfleet.checks.time_step.MAX_DT_S``.

For every model in description/ and every step dt asked for, it brings one arm up
alone, moves every joint +0.3 rad (kept 0.05 rad inside the limits), and prints
whether bring-up succeeded, the largest |q_ref - q| during the move and |q - target|
0.2 s after it, against issue #2's figures (1e-3 rad, 1e-4 rad).

    python benchmarks/dt_limits.py                       # the default steps
    python benchmarks/dt_limits.py 0.002 0.0022 --model panda

To measure beyond the range the library accepts, it raises ``MAX_DT_S`` for its own
process only: a measurement tool, not a way to run a world.
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse

import numpy as np

from armfleet.checks import time_step
from armfleet.description import ModelLibrary

DEFAULT_STEPS = (0.001, 0.002, 0.0022, 0.003, 0.004, 0.0046, 0.005, 0.01, 0.02)
MAX_TRACKING_ERROR_RAD, FINAL_ERROR_RAD, SETTLE_S = 1e-3, 1e-4, 0.2


def measure(model: str, dt: float) -> str:
    """One line: bring-up, tracking and settling of ``model`` at ``dt``."""
    with armfleet.World(dt=dt) as world:
        try:
            arm = world.spawn("bob", model=model)
        except armfleet.ArmfleetError as exc:
            return f"bring-up FAILED: {exc}"
        lower, upper = arm.joint_limits
        target = np.clip(arm.positions + 0.3, lower + 0.05, upper - 0.05)
        arm.move_to(target)
        worst, deadline = 0.0, world.time + 10.0
        while arm.is_moving and world.time < deadline:
            world.step()
            worst = max(worst, arm.position_controller.tracking_error)
        world.run(SETTLE_S)
        final = float(np.abs(arm.positions - target).max())
        ok = worst < MAX_TRACKING_ERROR_RAD and final < FINAL_ERROR_RAD and not arm.is_moving
        verdict = "ok" if ok else "OUT OF FIGURES"
        return f"{verdict}: max tracking {worst:.2e} rad, settled {final:.2e} rad, {arm.mode.value}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("steps", nargs="*", type=float, default=DEFAULT_STEPS, help="dt [s]")
    parser.add_argument("--model", action="append", help="only these models (repeatable)")
    args = parser.parse_args()
    time_step.MAX_DT_S = max(args.steps)  # this process only, to look past the bound
    for model in args.model or ModelLibrary().names:
        for dt in args.steps:
            print(f"{model:6s} dt={dt:<7g} {measure(model, dt)}", flush=True)


if __name__ == "__main__":
    main()
