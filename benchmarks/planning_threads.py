"""What a planned move asked by another thread costs the stepping thread, against the plan.

In the shared cell, bob is sent across the table and back, again and again, with
``world.start_planned_move`` (how the live API plans: read on the stepping thread, planned
on a planning thread, started on the stepping thread; see docs/planning.md, "The world
keeps running while anyone plans"). Per move it times, on the stepping thread, the read
(``start_planned_move`` itself) and the start (the step boundary that runs it, less a
median step: the plan is checked again against the world as it is and handed to the
controllers; the proof is kept when nothing moved, which ``--static`` shows), and,
as the baseline measured in the same run, the whole plan made on the stepping thread
(``world.plan``), which is what held the world before. It prints medians and maxima, the
share of the plan the stepping thread still spends, and writes
benchmarks/results/planning_threads.json.

    python benchmarks/planning_threads.py            # 20 moves
    python benchmarks/planning_threads.py --short    # 2 moves (CI)
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

RESULTS = Path(__file__).resolve().parent / "results"
#: bob's goal across the table (docs/planning.md); he goes back to where he started.
GOAL = np.array([-0.7, 0.6, 0.0, -1.6, 0.0, 2.2, 0.78])
#: Longest wait for one plan to come back [s].
WAIT_S = 30.0
#: Each plan's budget [s]: generous, so that a busy machine does not fail a plan.
TIMEOUT_S = 5.0


def one_move(world: armfleet.World, goal: np.ndarray) -> tuple[float, float, float]:
    """(read, start, plan on the stepping thread) of one move to ``goal`` [s]."""
    mark = time.perf_counter()
    baseline = world.plan({"bob": goal}, timeout_s=TIMEOUT_S)
    planned_s = time.perf_counter() - mark
    del baseline
    mark = time.perf_counter()
    answer = world.start_planned_move({"bob": goal}, float, timeout_s=TIMEOUT_S)
    read_s = time.perf_counter() - mark
    # The world steps while the plan is made, as a served world does: the start then checks
    # the plan against the world as it is (the same world here, moved on by some steps).
    steps: list[float] = []
    deadline = time.monotonic() + WAIT_S
    while not answer.done() and time.monotonic() < deadline:
        mark = time.perf_counter()
        world.process_requests()
        world.step()
        steps.append(time.perf_counter() - mark)
    start_s = steps[-1] - float(np.median(steps))  # the step boundary that started it
    world.run(answer.result(timeout=0) + 0.3)
    return read_s, start_s, planned_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="2 moves (CI smoke, not a timing)")
    parser.add_argument("--moves", type=int, default=20)
    parser.add_argument(
        "--static", action="store_true",
        help="take the loose cubes out first: nothing then moves while bob plans, and a plan "
        "starts without being proven again",
    )  # fmt: skip
    parser.add_argument("--json", type=Path, default=RESULTS / "planning_threads.json")
    options = parser.parse_args()
    moves = 2 if options.short else options.moves
    with armfleet.launch("shared_cell", viewer=False) as world:
        if options.static:
            for name, obj in world.objects.items():
                if not obj.is_static:
                    world.remove_object(name)
        world.run(0.5)
        goals = (GOAL, world.arm("bob").positions)
        rows = np.array([one_move(world, goals[i % 2]) for i in range(moves)]) * 1000.0
    names = ("read_ms", "start_ms", "plan_on_stepping_thread_ms")
    figures: dict[str, Any] = {
        "machine": platform.platform(),
        "moves": moves,
        "static": options.static,
        **{
            name: {"median": float(np.median(rows[:, k])), "max": float(rows[:, k].max())}
            for k, name in enumerate(names)
        },
    }
    held = rows[:, 0] + rows[:, 1]
    figures["stepping_share_of_plan"] = float(np.median(held / rows[:, 2]))
    print(f"{moves} planned moves of bob in the shared cell, ms on the stepping thread:")
    for name in names:
        median, longest = figures[name]["median"], figures[name]["max"]
        print(f"  {name:28s} median {median:7.2f}   max {longest:7.2f}")
    share = figures["stepping_share_of_plan"]
    print(f"  stepping thread's share of the plan, median: {share:.2f}")
    options.json.parent.mkdir(parents=True, exist_ok=True)
    options.json.write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main()
