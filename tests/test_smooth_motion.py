"""Planned motions pass through their waypoints without stopping (issue 27, item 2).

What is asserted comes from outside the timing: the joints' limits from the controllers'
parameters, the executed samples (the ``SampledMotion`` the arms follow) differentiated
here, PyBullet's contacts and distances while the world runs them, the arms' measured
positions, and the rest-to-rest reference timing of the same waypoints.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np
import pytest

import armfleet
from armfleet.planning import Plan
from armfleet.planning.path_timing import JointLimits, TimedPath
from tests.planning_helpers import Watch, gap_at, shared_cell, swap_goals, tool_down

#: A relative slack on velocity and acceleration for floating point (profiles reach them).
LIMIT_SLACK = 1e-9
#: The jerk is piecewise constant, so the difference of the acceleration over one period
#: divided by it is bounded by the jerk limit exactly; this covers rounding of a ~1e-6
#: difference divided by 1e-3 s.
JERK_SLACK = 1e-6
#: The arms track their reference to this (tests/test_tracking.py's bound) [rad].
MAX_TRACKING_ERROR_RAD = 1e-5
#: PyBullet's hulls are up to 2.5 mm fatter than the planner's (test_planning_scene.py),
#: so a proven-clear state keeps at least the clearance minus this in PyBullet [m].
HULL_TOLERANCE_M = 2.5e-3
#: A smooth plan takes at most this share of the rest-to-rest timing of its waypoints
#: when a joint that sets a segment's duration keeps its direction through a corner: the
#: swap's (~0.87). A corner saves nothing when those joints turn back there (they stop
#: either way): the one-Panda plan's only corner is such, and its share is 1. Never more
#: than 1: the worst case is the rest-to-rest timing itself.
SHORTER_THAN = {"one Panda": 1.0 + 1e-9, "two Pandas jointly": 0.95}


def limits_of(world: armfleet.World, arms: tuple[str, ...]) -> JointLimits:
    """The planned joints' limits, read from the controllers' parameters."""
    velocity, acceleration, jerk = [], [], []
    for name in arms:
        controller = world.arm(name).position_controller
        velocity.append(controller.max_velocity)
        acceleration.append(np.full(7, float(controller.parameters["max_acceleration_rad_s2"])))
        jerk.append(np.full(7, float(controller.parameters["max_jerk_rad_s3"])))
    return JointLimits(np.concatenate(velocity), np.concatenate(acceleration), np.concatenate(jerk))


#: Search iterations of the plans below: a budget reseeds the search from its start and
#: goal, so the path is the same whatever the process planned before (under a time budget
#: it depends on the tests a worker ran first, and one such path had nothing to blend).
BUDGET = 2000


def one_panda_across(world: armfleet.World) -> Plan:
    """bob's tool over toby's side of the table, past the post."""
    return world.arm("bob").plan(tool_down((0.55, 0.25, 0.45)), budget=BUDGET)


def two_pandas_swap(world: armfleet.World) -> Plan:
    """bob and toby swap sides around the post, planned jointly (14 joints)."""
    return world.plan(swap_goals(world), budget=BUDGET)


PLANS = [
    pytest.param(one_panda_across, "one Panda", id="one Panda"),
    pytest.param(two_pandas_swap, "two Pandas jointly", id="two Pandas jointly"),
]


@pytest.mark.parametrize(("make", "case"), PLANS)
def test_the_executed_samples_keep_every_limit_and_start_and_end_at_rest(
    make: Callable[[armfleet.World], Plan], case: str
) -> None:
    """Every period of the executed motion: |v|, |a| and the finite-difference jerk of
    every joint within its limits, the velocity the derivative of the position; it
    starts at rest at the start and ends at rest exactly at the goal, passes its
    waypoints without stopping, and is shorter than rest to rest."""
    with shared_cell() as world:
        plan = make(world)
        assert len(plan.waypoints) >= 3, plan  # corners to pass, or the test is idle
        limits = limits_of(world, plan.arms)
        period = world.arm(plan.arms[0]).position_controller.period
        motion = plan.timing.sample(period)
        start = plan.timing.at(np.array([0.0]))
        position = np.vstack([start[0], motion.position])
        velocity = np.vstack([start[1], motion.velocity])
        acceleration = np.vstack([start[2], motion.acceleration])
        peaks = {
            "velocity": float((np.abs(velocity) / limits.velocity).max()),
            "acceleration": float((np.abs(acceleration) / limits.acceleration).max()),
            "jerk": float((np.abs(np.diff(acceleration, axis=0)) / period / limits.jerk).max()),
        }
        assert peaks["velocity"] <= 1 + LIMIT_SLACK, peaks
        assert peaks["acceleration"] <= 1 + LIMIT_SLACK, peaks
        assert peaks["jerk"] <= 1 + JERK_SLACK, peaks
        assert peaks["acceleration"] > 0.99, peaks  # a limit binds: the check has teeth
        # The velocity is the derivative of the position: trapezoids over one period,
        # exact but for j * period^2 / 12 (jerk-limited, piecewise-cubic position).
        np.testing.assert_allclose(
            np.diff(position, axis=0) / period,
            (velocity[1:] + velocity[:-1]) / 2,
            atol=float(limits.jerk.max()) * period**2,
        )
        np.testing.assert_array_equal(position[0], plan.waypoints[0])
        assert not velocity[0].any() and not acceleration[0].any()
        np.testing.assert_array_equal(position[-1], plan.waypoints[-1])
        assert not velocity[-1].any() and not acceleration[-1].any()
        # The last period arrives at rest: from rest, with |j| <= j_max, a joint moves at
        # most j_max * period^3 / 6 in one period (no jump to the goal).
        last_step = np.abs(position[-2] - position[-1])
        assert (last_step <= limits.jerk * period**3 / 6 * (1 + JERK_SLACK)).all(), last_step
        # Every inner waypoint is passed, in motion.
        arrivals = plan.timing.at(plan.timing.times[1:-1])
        np.testing.assert_allclose(arrivals[0], plan.waypoints[1:-1], atol=1e-9)
        assert (np.abs(arrivals[1]).max(axis=1) > 0.05).all(), arrivals[1]
        reference = TimedPath(plan.waypoints, limits)
        ratio = plan.timing.duration / reference.duration
        print(f"{plan}: {plan.timing.duration:.3f} s against {reference.duration:.3f} s")
        assert ratio <= SHORTER_THAN[case], ratio


def test_a_smooth_swap_around_the_post_touches_nothing_and_is_followed() -> None:
    """The two-arm swap executed in PyBullet: no contact on /collisions and no stop, both
    arms leave on the same step and stop on the same step, the reference each follows is
    the executed samples, the arms track it to the tracking tolerance, and along the
    samples (every 10 ms, in a scratch cell) PyBullet keeps the arms apart and off the
    post by the clearance, less the hulls' difference. The samples really leave the
    polyline (by more than the clearance allows for free)."""
    with shared_cell() as world:
        bob, toby = world.arm("bob"), world.arm("toby")
        plan = two_pandas_swap(world)
        period = bob.position_controller.period
        motion = plan.timing.sample(period)
        starts = {"bob": bob.positions, "toby": toby.positions}
        positions: list[dict[str, np.ndarray]] = []
        watch = Watch(world)

        def on_step(w: armfleet.World) -> None:
            watch(w)
            positions.append({name: arm.positions.copy() for name, arm in w.arms.items()})

        duration = world.execute(plan)
        world.run(duration + 0.2, on_step=on_step)
        assert watch.contacts == [] and watch.stops == 0
        left = {name: watch.first_step_leaving(name, starts[name]) for name in plan.arms}
        assert left["bob"] == left["toby"] == 0, left
        assert watch.last_step_moving("bob") == watch.last_step_moving("toby")
        for name in plan.arms:
            columns = plan.columns(name)
            followed = np.array([refs[name] for refs in watch.references[: motion.steps]])
            np.testing.assert_allclose(followed, motion.position[:, columns], atol=1e-12)
            measured = np.array([row[name] for row in positions[: motion.steps]])
            assert np.abs(measured - followed).max() < MAX_TRACKING_ERROR_RAD
        off_line = _distance_from_polyline(motion.position, plan.waypoints)
        assert off_line > 1e-3, off_line
    with shared_cell() as scratch:
        closest = {"arms": 1.0, "post": 1.0}
        for row in motion.position[::10]:
            at = {"bob": row[plan.columns("bob")], "toby": row[plan.columns("toby")]}
            closest["arms"] = min(closest["arms"], gap_at(scratch, at, "bob", "toby"))
            for arm in ("bob", "toby"):
                closest["post"] = min(closest["post"], gap_at(scratch, at, arm, "post"))
        print(f"closest along the samples: {closest}")
        assert min(closest.values()) > plan.clearance_m - HULL_TOLERANCE_M, closest


def _distance_from_polyline(samples: np.ndarray, waypoints: np.ndarray) -> float:
    """The largest joint-space distance [rad] of a sample from the nearest polyline point."""
    worst = 0.0
    for row in samples[::5]:
        nearest = np.inf
        for a, b in itertools.pairwise(waypoints):
            delta = b - a
            s = float(np.clip((row - a) @ delta / max(float(delta @ delta), 1e-18), 0.0, 1.0))
            nearest = min(nearest, float(np.linalg.norm(row - (a + s * delta))))
        worst = max(worst, nearest)
    return worst
