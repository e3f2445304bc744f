"""The shipped sweep scenarios reach and crossing, run in-process as a sweep's worker runs
them (a headless launch, the task with a seeded generator), checked against the world:
the tool frames on /tf, the protective stops, the contacts PyBullet reports."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from ompl import util as ou

import armfleet
from armfleet.messages import ArmMode
from armfleet.planning import PoseGoal
from armfleet.scenarios.crossing import Crossing, cross, crossing, draw_crossing
from armfleet.scenarios.reach import reach, reach_targets, spawn_row
from armfleet.scenarios.reach_targets import draw_row_targets, draw_targets, pose_error
from armfleet.sweeps.definition import load_sweep

#: The task's tolerances: a reach target within 5 mm and 2 degrees, a crossing goal
#: within 1 mm and 0.5 degrees.
REACH_M, REACH_RAD = 0.005, math.radians(2.0)
GOAL_M, GOAL_RAD = 0.001, math.radians(0.5)
#: The controllers track a Ruckig reference to ~3e-6 rad when nothing touches the arm.
TRACKING_RAD = 1e-4
#: OMPL's seed in the crossing tests (as the sweep runner reseeds it per run).
OMPL_SEED = 4242


@contextmanager
def launched(spec: str) -> Iterator[armfleet.World]:
    world = armfleet.launch(spec, viewer=False)
    try:
        yield world
    finally:
        world.close()


def reseed_ompl(seed: int) -> None:
    """Seed OMPL's random numbers again, quietly (it complains once numbers were drawn)."""
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(seed)
    finally:
        ou.setLogLevel(level)


# -- reach -----------------------------------------------------------------------------------
def test_reach_targets_are_poses_an_arm_can_be_brought_up_in() -> None:
    """Each target's configuration passes the world's own start-pose check (nothing
    within 1 mm of the arm itself or the floor), and an arm brought up there has its
    tool0 on /tf at the target (bring-up moves a link by at most 0.025 mm:
    armfleet.physics.start_clearance)."""
    with launched("reach") as world, launched("reach") as check:
        (arm,) = spawn_row(world, 1, 1.0)
        targets = draw_targets(arm, np.random.default_rng(7), 8)
        lower, upper = arm.joint_limits
        margin = 0.1 * (upper - lower)
        for target in targets:
            assert np.all(target.positions >= lower + margin)
            assert np.all(target.positions <= upper - margin)
            assert target.pose[2, 3] >= 0.1
            check.spawn("arm0", "panda", arm.pose, initial_positions=target.positions)
            tool = check.tf.lookup("world", "arm0_tool0")
            np.testing.assert_allclose(tool, target.pose, atol=5e-5)
            check.remove("arm0")


@pytest.mark.parametrize("seed", [0, 1])
def test_reach_ends_with_every_tool_at_its_target(seed: int) -> None:
    """Two Pandas 1 m apart: both tools end on their targets (/tf, not the task's count),
    nothing stopped, and the task's metrics are these steps' metrics, bit for bit."""
    with launched("reach") as world:
        arms = spawn_row(world, 2, 1.0)
        targets = draw_row_targets(arms, np.random.default_rng(seed), 1)
        metrics = reach_targets(world, targets).metrics(2, 0.005, 2.0)
        for arm in arms:
            error_m, error_rad = pose_error(
                world.tf.lookup("world", f"{arm.name}_tool0"), targets[arm.name][0].pose
            )
            assert error_m < REACH_M and error_rad < REACH_RAD
            assert arm.mode is ArmMode.HOLDING
        assert world.safety.stops == 0
    assert metrics["reached_fraction"] == 1.0
    assert metrics["stops"] == 0 and metrics["arms"] == 2 and metrics["targets"] == 2
    assert 0.0 < float(metrics["max_tracking_error_rad"]) < TRACKING_RAD
    with launched("reach") as world:
        assert reach(world, np.random.default_rng(seed)) == metrics


def test_reach_is_a_function_of_its_seed() -> None:
    """The same seed twice: the same metrics, bit for bit (three arms, two rounds);
    another seed: other targets."""
    runs = []
    for _ in range(2):
        with launched("reach") as world:
            runs.append(reach(world, np.random.default_rng(3), arm_count=3, targets_per_arm=2))
    assert runs[0] == runs[1]
    assert runs[0]["targets"] == 6
    with launched("reach") as world:
        arms = spawn_row(world, 2, 1.0)
        first, second = (draw_row_targets(arms, np.random.default_rng(s), 1) for s in (3, 4))
    for name in first:
        assert not np.allclose(first[name][0].pose, second[name][0].pose)


def test_neighbours_that_touch_are_an_outcome_not_an_error() -> None:
    """0.6 m apart (seed 5), the two arms reach into each other: both stop, touching each
    other, and the run still returns its metrics."""
    with launched("reach") as world:
        metrics = reach(world, np.random.default_rng(5), arm_count=2, spacing_m=0.6)
        assert world.safety.stops == 2
        assert all(arm.mode is ArmMode.PROTECTIVE_STOP for arm in world.arms.values())
        assert "arm1" in world.contacts.touching_bodies("arm0")
    assert metrics["stops"] == 2 and metrics["reached_fraction"] == 0.0
    assert float(metrics["max_tracking_error_rad"]) > TRACKING_RAD  # pushed off its path


@pytest.mark.parametrize(
    "keywords",
    [{"arm_count": 0}, {"arm_count": 2.5}, {"arm_count": "2"}, {"spacing_m": -1.0}],
    ids=["no arms", "half an arm", "text", "negative spacing"],
)
def test_bad_reach_parameters_raise_before_anything_is_spawned(
    keywords: dict[str, object],
) -> None:
    with launched("reach") as world:
        with pytest.raises(armfleet.InvalidNumber):
            reach(world, np.random.default_rng(0), **keywords)  # type: ignore[arg-type]
        assert world.arms == {}


# -- crossing --------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_crossing_ends_with_both_tools_at_their_goals(seed: int) -> None:
    """Planned from random starts across the post: both tcps end on their goals (/tf), at
    the plan's last joint positions, with no stop and no contact of any kind; run again
    with OMPL reseeded, the task gives the same metrics (but the planning time)."""
    reseed_ompl(OMPL_SEED)
    with launched("crossing") as world:
        poses = draw_crossing(world, np.random.default_rng(seed))
        outcome = cross(world, poses)
        assert outcome.plan is not None
        for name, goal in poses.goals.items():
            error_m, error_rad = pose_error(world.tf.lookup("world", f"{name}_tcp"), goal)
            assert error_m < GOAL_M and error_rad < GOAL_RAD
            arm = world.arm(name)
            np.testing.assert_allclose(arm.positions, outcome.plan.path(name)[-1], atol=1e-3)
            assert arm.mode is ArmMode.HOLDING
        assert world.safety.stops == 0
        assert world.contacts.total_contacts == 0
    metrics = outcome.metrics()
    assert metrics["success"] and metrics["planned"] and metrics["failure"] == ""
    assert float(metrics["path_length_rad"]) > 0.0 and float(metrics["planning_time_s"]) > 0.0
    reseed_ompl(OMPL_SEED)
    with launched("crossing") as world:
        again = crossing(world, np.random.default_rng(seed))
    for run in (metrics, again):
        del run["planning_time_s"]
    assert again == metrics


def test_reseeding_ompl_repeats_a_search() -> None:
    """Plan A, reseed, plan B, reseed, plan B again: the same waypoints, bit for bit,
    although B needs a search (as the sweep runner relies on between runs)."""
    with launched("crossing") as world:
        goals = [
            {n: PoseGoal(p, "world", "tcp") for n, p in draw_crossing(world, rng).goals.items()}
            for rng in (np.random.default_rng(1), np.random.default_rng(3))
        ]
        world.plan(goals[0])
        plans = []
        for _ in range(2):
            reseed_ompl(OMPL_SEED)
            plans.append(world.plan(goals[1]))
    assert plans[0].samples > 0
    assert plans[0].samples == plans[1].samples
    np.testing.assert_array_equal(plans[0].waypoints, plans[1].waypoints)


def test_a_goal_in_the_post_is_an_outcome_not_an_error() -> None:
    """bob's goal inside the post: no plan (every IK solution touches it), nothing
    moves, and the metrics say why."""
    with launched("crossing") as world:
        drawn = draw_crossing(world, np.random.default_rng(0))
        inside = drawn.goals["bob"].copy()
        inside[:3, 3] = world.object("post").position
        outcome = cross(world, Crossing(drawn.starts, {**drawn.goals, "bob": inside}))
        at_start = {name: arm.positions for name, arm in world.arms.items()}
        world.run(0.2)
        for name, arm in world.arms.items():
            np.testing.assert_allclose(arm.positions, at_start[name], atol=1e-6)
    metrics = outcome.metrics()
    assert metrics["at_start"] and not metrics["planned"] and not metrics["success"]
    assert metrics["failure"] == "GOAL_IN_COLLISION"
    assert math.isnan(float(metrics["planning_time_s"]))
    assert math.isnan(float(metrics["goal_error_m"]))


# -- the specs' sweep sections --------------------------------------------------------------
@pytest.mark.parametrize(
    ("scenario", "task", "targets"),
    [
        ("reach", reach, ["task.arm_count", "task.spacing_m"]),
        ("crossing", crossing, ["objects.post.at_m"]),
    ],
)
def test_the_shipped_sweeps_name_these_tasks(
    scenario: str, task: object, targets: list[str]
) -> None:
    definition = load_sweep(scenario)
    assert definition.task.name == f"{task.__module__}:{task.__name__}"  # type: ignore[attr-defined]
    assert [parameter.target for parameter in definition.randomization] == targets
