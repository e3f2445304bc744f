"""What the benchmark scripts share: a grid of Pandas and random targets near home."""

from __future__ import annotations

import math
import time

import numpy as np

import armfleet


def grid_spawn(world: armfleet.World, count: int) -> float:
    """Spawn ``count`` Pandas on a square-ish 1 m grid; return the wall time it took [s]."""
    columns = math.ceil(math.sqrt(count))
    started = time.perf_counter()
    for i in range(count):
        world.spawn(f"arm{i}", at=(float(i % columns), float(i // columns)))
    return time.perf_counter() - started


def retarget(world: armfleet.World, rng: np.random.Generator, spread_rad: float = 0.6) -> None:
    """Give every arm at rest a random target within ``spread_rad`` of home and its limits.

    Neighbours 1 m apart can still touch; an arm in protective stop is reset and
    sent home.
    """
    for arm in world.arms.values():
        if arm.is_moving:
            continue
        home = np.array(arm.description.home)
        lower, upper = arm.joint_limits
        target = np.clip(home + rng.uniform(-spread_rad, spread_rad, size=len(home)), lower, upper)
        try:
            arm.move_to(target)
        except armfleet.ArmfleetError:  # protective stop after touching a neighbour
            arm.reset()
            arm.move_to(home)


def timed_run(world: armfleet.World, rng: np.random.Generator, sim_s: float) -> float:
    """Run ``sim_s`` simulated seconds flat out, re-targeting every 0.5 s; the wall time [s]."""
    wall = 0.0
    for _ in range(round(sim_s / 0.5)):
        retarget(world, rng)
        started = time.perf_counter()
        world.run(0.5)
        wall += time.perf_counter() - started
    return wall
