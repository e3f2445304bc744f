"""examples/shared_cell.py: two arms swap cubes across one table without touching.

The example is imported and run on a launched shared cell (fewer cubes than its
default 20, to keep the test short); what it achieved is checked from the world
itself, not from the example's own tally: where each cube ends, /collisions, the
protective stops, and /<arm>/status.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import armfleet
from armfleet.messages import ArmMode, ArmStatus, CollisionReport

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "shared_cell.py"
#: The table of launch_specs/shared_cell.yaml: x in [0.25, 0.65], y in [-0.5, 0.5], top 0.15 m.
TABLE_X_M, TABLE_Y_M, TABLE_TOP_M = (0.25, 0.65), (-0.5, 0.5), 0.15
MIDDLE_X_M = 0.45  # the line between bob's half and toby's
CUBE_HALF_M = 0.02
WALL_HALF_M = 0.02  # the walls and the post stand on the middle line, 4 cm thick / 8 cm wide
#: A cube resting flat on the table has its centre this high, give or take 1 mm (PyBullet's
#: contact penetration is well under that) and its top face up within 2 degrees.
REST_Z_M, REST_Z_TOL_M, UPRIGHT_TOL_DEG = TABLE_TOP_M + CUBE_HALF_M, 1e-3, 2.0
#: The cubes swap places: each ends on the spot a cube of the other half started from,
#: within the example's start jitter (5 mm in x and y) and its 10 mm placing tolerance.
SWAP_TOL_M = 0.005 * math.sqrt(2) + 0.010


@pytest.fixture(scope="module")
def example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("shared_cell_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def cell() -> Iterator[armfleet.World]:
    world = armfleet.launch("shared_cell", viewer=False)
    try:
        yield world
    finally:
        world.close()


def test_cubes_cross_to_the_other_half_without_arm_contacts(
    example: ModuleType, cell: armfleet.World
) -> None:
    world = cell
    cubes = example.set_out_cubes(world, 4, np.random.default_rng(1))
    start = {cube.name: world.object(cube.name).position.copy() for cube in cubes}
    touches: list[tuple[str, str]] = []  # arm-arm, arm-static object, arm-floor contacts

    def on_collisions(report: CollisionReport) -> None:
        arms, objects = world.arms, world.objects
        for c in report.contacts:
            for arm, other in ((c.body_a, c.body_b), (c.body_b, c.body_a)):
                obstacle = other in arms or other not in objects or objects[other].is_static
                if arm in arms and other != arm and obstacle:
                    touches.append(c.pair)

    moving: dict[str, set[float]] = {"bob": set(), "toby": set()}

    def on_status(status: ArmStatus) -> None:
        if status.mode is ArmMode.MOVING:
            moving[status.arm].add(round(status.stamp, 3))

    world.bus.subscribe("/collisions", on_collisions)
    for name in moving:
        world.bus.subscribe(f"/{name}/status", on_status)

    outcome = example.work(world, cubes, 1, quiet=True)

    assert not touches  # no arm touched the other arm, the table, post, walls or floor
    assert world.safety.stops == 0
    for name, began in start.items():
        cube = world.object(name)
        x, y, z = cube.position
        # on the other half, clear of the wall line, within the table top
        assert (x - MIDDLE_X_M) * (began[0] - MIDDLE_X_M) < 0, name
        assert abs(x - MIDDLE_X_M) > CUBE_HALF_M + WALL_HALF_M, name
        assert TABLE_X_M[0] + CUBE_HALF_M < x < TABLE_X_M[1] - CUBE_HALF_M, name
        assert TABLE_Y_M[0] + CUBE_HALF_M < y < TABLE_Y_M[1] - CUBE_HALF_M, name
        # resting flat on the table, not tipped over or stacked
        assert abs(z - REST_Z_M) < REST_Z_TOL_M, name
        up = world.tf.lookup("world", name)[:3, 2]
        assert math.degrees(math.acos(min(1.0, abs(up[2])))) < UPRIGHT_TOL_DEG, name
        other_half = [p for p in start.values() if (p[0] - MIDDLE_X_M) * (x - MIDDLE_X_M) > 0]
        gap_m = min(float(np.linalg.norm(p[:2] - (x, y))) for p in other_half)
        assert gap_m < SWAP_TOL_M, (name, gap_m)  # on the spot a cube came from
    for a, b in itertools.combinations(start, 2):  # no two cubes in one place
        gap = np.abs(world.object(a).position[:2] - world.object(b).position[:2])
        assert gap.max() > 2 * CUBE_HALF_M, (a, b)
    # the arms worked at the same time (statuses at 10 Hz), and are home and still
    assert moving["bob"] & moving["toby"]
    for arm in world.arms.values():
        assert not arm.is_moving
        assert np.allclose(arm.positions, arm.description.home, atol=0.01), arm.name
    # and the example saw the same
    assert outcome.success, str(outcome)
    assert outcome.placed == outcome.cubes == 4
    assert outcome.arm_arm_contacts == outcome.arm_obstacle_contacts == 0


def run_example(*args: str, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}  # never near a shared world
    return subprocess.run(
        [sys.executable, str(EXAMPLE), "--no-viewer", "--quiet", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
        check=False,
    )


def test_headless_run_exits_zero_when_its_goals_are_met(tmp_path: Path) -> None:
    result = run_example("--cubes", "1", "--seed", "2", tmp_path=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1/1" in result.stdout and "success" in result.stdout.splitlines()[-1]


@pytest.mark.parametrize(
    ("args", "named"),
    [
        pytest.param(["--cubes", "many"], "--cubes", id="--cubes many -> exit 2, one line"),
        pytest.param(
            ["--cubes", "21"], "[1, 20]", id="more cubes than spots -> exit 2, range named"
        ),
        pytest.param(["--seed", "-1"], "--seed", id="negative seed -> exit 2, one line"),
    ],
)
def test_bad_arguments_are_one_line(args: list[str], named: str, tmp_path: Path) -> None:
    result = run_example(*args, tmp_path=tmp_path)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], result.stderr
    assert "Traceback" not in result.stderr and not result.stdout
