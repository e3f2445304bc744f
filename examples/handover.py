"""Bob picks a bar from a table, hands it to toby in mid-air, and toby puts it on the mat.

    python examples/handover.py                  # in the viewer (open the printed URL)
    python examples/handover.py --no-viewer      # headless, prints the outcome
    python examples/handover.py --runs 20        # 20 seeded runs, bar moved a little each time

The scene is launch_specs/handover.yaml; the choreography is the handover scenario
(armfleet/scenarios/handover.py), which ``armfleet sweep handover`` runs for
many seeds on Ray.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

import armfleet
from armfleet.scenarios.handover import (
    TOLERANCE_M,
    Watch,
    hand_over,
    placement_error_m,
)

JITTER_M, JITTER_DEG = 0.02, 10.0  # random start of the bar in --runs
__all__ = ["Watch", "hand_over"]  # the scenario's, used here and by tests/test_handover.py


@dataclass(frozen=True)
class Outcome:
    seed: int
    picked: bool  # bob held the bar after closing on it
    error_m: float  # bar centre from the mat's centre, 2.1 cm up
    steps_unheld: int
    arm_contacts: int
    stops: int

    @property
    def success(self) -> bool:
        return (
            self.picked
            and self.error_m <= TOLERANCE_M
            and self.steps_unheld == 0
            and self.arm_contacts == 0
            and self.stops == 0
        )


def run(seed: int, *, viewer: bool = False) -> Outcome:
    """One handover with the bar moved by up to 2 cm / 10 deg from its spot (seed 0: not)."""
    world = armfleet.launch("handover", viewer=viewer)
    try:
        rng = np.random.default_rng(seed)
        x, y, z = world.object("bar").position
        if seed:
            dx, dy = rng.uniform(-JITTER_M, JITTER_M, 2)
            yaw = rng.uniform(-JITTER_DEG, JITTER_DEG)
            world.object("bar").set_pose((x + dx, y + dy, z), (0.0, 0.0, yaw))
        if viewer and world.viewer is not None:
            print(f"viewer: {world.viewer.url}")
        watch = hand_over(world, realtime=viewer)
        error = placement_error_m(world)
        return Outcome(
            seed, watch.picked, error, watch.steps_unheld, watch.arm_contacts, world.safety.stops
        )
    finally:
        world.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-viewer", action="store_true", help="run headless")
    parser.add_argument("--runs", type=int, default=0, help="seeded headless runs")
    args = parser.parse_args()
    if args.runs:
        outcomes = [run(seed) for seed in range(args.runs)]
        for o in outcomes:
            print(
                f"seed {o.seed:2d}: {'ok  ' if o.success else 'FAIL'} "
                f"bar {o.error_m * 1000:5.1f} mm from target, unheld steps {o.steps_unheld}, "
                f"arm contacts {o.arm_contacts}, stops {o.stops}"
            )
        wins = sum(o.success for o in outcomes)
        print(f"success: {wins}/{len(outcomes)} ({100 * wins / len(outcomes):.0f} %)")
    else:
        outcome = run(0, viewer=not args.no_viewer)
        print(outcome, "success" if outcome.success else "FAILED")


if __name__ == "__main__":
    main()
