"""Planning while another arm moves (issue 16: "bob can plan while toby is moving, with
neither stopping", and "if no such plan exists ..., the error says which arm was in the
way"). Executed in PyBullet, in the shipped shared cell."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armfleet
from armfleet.messages import PlannedMotion
from armfleet.planning import FailureReason, PlanningFailed
from tests.planning_helpers import (
    ARRIVAL_RAD,
    HOLD_DRIFT_RAD,
    Watch,
    body_ids,
    gap,
    gap_at,
    shared_cell,
    tool_down,
)
from tests.test_planning import CLEARANCE_SLACK_M

#: toby's tool over the post, then back to its side; bob's tool into the place toby left.
TOBY_OVER_POST_M = (0.47, 0.0, 0.65)
TOBY_BACK_M = (0.65, 0.25, 0.45)
BOB_INTO_THE_MIDDLE_M = (0.43, 0.0, 0.65)


def test_bob_plans_and_moves_while_toby_runs_a_planned_motion_through_the_same_space() -> None:
    """toby leaves the middle of the table on a planned motion; while it runs, bob plans a
    move into the place toby is leaving (his goal overlaps toby's start, by PyBullet)
    and executes it. They move at the same time, neither stops, toby's motion runs to
    its planned end, no contact, and PyBullet's distance between them stays at the
    clearance less the hull slack."""
    with shared_cell() as world:
        bob, toby = world.arm("bob"), world.arm("toby")
        world.run(toby.move_to_pose(tool_down(TOBY_OVER_POST_M, math.pi), avoid_collisions=True))
        world.run(0.2)
        toby_start = toby.positions
        announced: list[PlannedMotion] = []
        world.bus.subscribe("/toby/planned_motion", announced.append)
        watch = Watch(world)
        toby_duration = toby.move_to_pose(tool_down(TOBY_BACK_M, math.pi), avoid_collisions=True)
        watch.run(0.05)
        assert toby.is_moving
        plan = bob.plan(tool_down(BOB_INTO_THE_MIDDLE_M))
        bob_goal = plan.path("bob")[-1]
        with shared_cell() as scratch:  # bob's goal is where toby was: the same space
            overlap = gap_at(scratch, {"bob": bob_goal, "toby": toby_start}, "bob", "toby")
        assert overlap < 0.0, overlap
        nearest = math.inf
        ids = body_ids(world)

        def on_step(w: armfleet.World) -> None:
            nonlocal nearest
            watch(w)
            nearest = min(nearest, gap(w, "bob", "toby", ids=ids))

        bob_duration = world.execute(plan)
        world.run(max(bob_duration, toby_duration) + 0.3, on_step=on_step)
        assert watch.contacts == [] and watch.stops == 0
        assert nearest >= plan.clearance_m - CLEARANCE_SLACK_M, nearest
        together = sum(flags["bob"] and flags["toby"] for flags in watch.moving)
        assert together * world.dt > 0.1, together  # they really moved at the same time
        # toby ran to the end of its announced motion without a break.
        toby_steps = [flags["toby"] for flags in watch.moving]
        end = watch.last_step_moving("toby")
        assert all(toby_steps[: end + 1])
        assert (end + 1) * world.dt == pytest.approx(announced[0].duration, abs=2 * world.dt)
        assert np.abs(bob.positions - bob_goal).max() < ARRIVAL_RAD
        assert np.abs(toby.positions - announced[0].positions[-1]).max() < ARRIVAL_RAD


def test_a_plan_blocked_by_a_moving_arm_names_it_and_nothing_moves() -> None:
    """toby sweeps (a plain straight move) through where bob's hand stands; bob's plan of
    a small move is refused whatever it waits: no path, blocking_arm toby, in one line,
    and bob is not sent anything."""
    with shared_cell() as world:
        bob, toby = world.arm("bob"), world.arm("toby")
        middle = toby.solve_ik(tool_down((0.40, 0.0, 0.56), math.pi))
        with shared_cell() as scratch:  # at the middle of its sweep toby is in bob's hand
            assert gap_at(scratch, {"toby": middle}, "bob", "toby") < 0.0
        side = np.array([0.9, 0, 0, 0, 0, 0, 0])
        world.run(toby.move_to(middle + side) + 0.2)
        toby.move_to(middle - side)
        world.run(0.02)
        sent: list[object] = []
        world.bus.subscribe("/bob/position_controller/commands", sent.append)
        world.bus.subscribe("/bob/planned_motion", sent.append)
        before = bob.positions
        goal = before - np.array([0.15, 0, 0, 0, 0, 0, 0])
        with pytest.raises(PlanningFailed) as failure:
            bob.move_to(goal, avoid_collisions=True)
        message = str(failure.value)
        assert failure.value.reason is FailureReason.NO_PATH and "\n" not in message
        assert failure.value.blocking_arm == "toby" and "toby" in message
        world.run(0.1)  # toby has not reached bob yet
        assert sent == [] and not bob.is_moving
        assert np.abs(bob.positions - before).max() < HOLD_DRIFT_RAD


#: toby crosses in front of the post, from one side of the table to the other.
TOBY_CROSSING_M = ((0.55, 0.3, 0.6), (0.55, -0.3, 0.6))
BOB_OVER_THE_POST_M = (0.45, 0.0, 0.65)


def test_a_plan_waits_at_its_start_for_a_moving_arm_to_pass() -> None:
    """toby crosses the table in front of the post; bob plans a move over the post that
    would meet toby if it started at once (PyBullet, with toby's recorded reference): the
    plan waits at its start (start_delay_s > 0), bob's reference holds still for that
    long, and the two pass with no contact and no stop."""
    with shared_cell() as world:
        bob, toby = world.arm("bob"), world.arm("toby")
        first, second = TOBY_CROSSING_M
        world.run(toby.move_to_pose(tool_down(first, math.pi), avoid_collisions=True) + 0.1)
        watch = Watch(world)
        toby_duration = toby.move_to_pose(tool_down(second, math.pi), avoid_collisions=True)
        watch.run(0.02)
        plan = bob.plan(tool_down(BOB_OVER_THE_POST_M))
        assert plan.start_delay_s > 0.0, plan
        planned_at = len(watch.moving)
        start = bob.positions
        duration = world.execute(plan)
        watch.run(max(duration, toby_duration) + 0.3)
        assert watch.contacts == [] and watch.stops == 0
        left = watch.first_step_leaving("bob", start) - planned_at
        assert left * world.dt == pytest.approx(plan.start_delay_s, abs=2 * world.dt)
        # Without the wait bob would have met toby: bob's path undelayed against toby's
        # reference as it was run, every 20 ms, in a scratch cell.
        toby_reference = [refs["toby"] for refs in watch.references[planned_at:]]
        steps = range(0, min(len(toby_reference), round(plan.timing.duration / world.dt)), 20)
        undelayed = plan.timing.at(np.array([(i + 1) * world.dt for i in steps]))[0]
        with shared_cell() as scratch:
            closest = min(
                gap_at(scratch, {"bob": row, "toby": toby_reference[i]}, "bob", "toby")
                for i, row in zip(steps, undelayed, strict=True)
            )
        print(f"undelayed closest {closest * 1000:.1f} mm, delay {plan.start_delay_s:.3f} s")
        assert closest < plan.clearance_m, closest
        assert np.abs(bob.positions - plan.waypoints[-1]).max() < ARRIVAL_RAD
