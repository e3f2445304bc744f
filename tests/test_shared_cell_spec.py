"""The shared cell of issue 16 (launch_specs/shared_cell.yaml) loads, and it is a real
obstacle course: a straight joint-space motion of bob from his half of the table to
toby's runs into the low wall between them in PyBullet."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import armfleet
from armfleet.messages import CollisionReport
from armfleet.spec import load_spec

#: bob's tool0 pointing down 0.31 m above the floor at (0.32, 0.20): his half of the
#: table, 4 cm short of cube_1, in front of wall_left (x = 0.43-0.47, y = 0.175-0.425,
#: top at 0.27 m; the fingertips hang ~0.1 m below tool0).
START = (0.36, -0.32, 0.22, -2.76, 0.11, 2.44, 0.48)
#: The same, at (0.60, 0.20): toby's half, beyond the wall.
GOAL = (0.19, 0.39, 0.15, -1.87, -0.07, 2.25, 0.37)


def cell_with_bob_at(positions: tuple[float, ...]) -> armfleet.World:
    """The shared cell with bob brought up at ``positions`` (refused if he touches anything)."""
    spec = load_spec("shared_cell")
    arms = tuple(
        replace(arm, initial_positions=positions) if arm.name == "bob" else arm for arm in spec.arms
    )
    return armfleet.launch(replace(spec, arms=arms), viewer=False)


def test_launch_check_accepts_the_shared_cell() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "launch", "shared_cell", "--check"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "ok: 2 arm(s) (panda)" in result.stdout


def test_a_straight_line_from_bobs_half_to_tobys_runs_into_the_wall() -> None:
    with cell_with_bob_at(GOAL):
        pass  # the world took bob there: nothing touches at the goal either
    with cell_with_bob_at(START) as world:
        reports: list[CollisionReport] = []
        world.bus.subscribe("/collisions", reports.append)
        world.run(0.05)
        assert not [c for r in reports for c in r.contacts if "bob" in (c.body_a, c.body_b)]
        bob = world.arm("bob")
        duration = bob.move_to(GOAL)
        world.run(duration + 0.2)
        touched = {
            (c.link_a, c.body_b) if c.body_a == "bob" else (c.link_b, c.body_a)
            for r in reports
            for c in r.contacts
            if "bob" in (c.body_a, c.body_b)
        }
        assert any(body == "wall_left" for _, body in touched), touched
        assert world.safety.stops > 0  # so PyBullet counted it as a collision
