"""Collision-free plans, executed in PyBullet (issue 16's proof).

Every assertion is about what the physics and the bus report, or about numbers computed
here independently: contacts on ``/collisions``, protective stops, where the arms end,
PyBullet's distances to the obstacles, the joints' limits from the controller
parameters, and the plan's own timing sampled densely. The cell is the shipped
``launch_specs/shared_cell.yaml``: two Pandas 0.9 m apart over a table with a post (a
cylinder of 4 cm radius up to 0.5 m) and two low walls.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.messages import FloatArray
from armfleet.planning import FailureReason, Plan, PlanningFailed
from armfleet.planning.path_timing import JointLimits, TimedPath
from armfleet.recording import open_recording
from tests.planning_helpers import (
    ARRIVAL_RAD,
    HOLD_DRIFT_RAD,
    Watch,
    body_ids,
    gap,
    gap_at,
    link_gap,
    shared_cell,
    swap_goals,
    tool_down,
    tool_position,
)

#: PyBullet's hulls are up to 2 mm fatter than the planner's (test_planning_scene.py), and
#: the arm tracks its reference to ~0.1 mrad (~0.1 mm at the tool): the clearance kept in
#: PyBullet is the planned one minus this [m].
CLEARANCE_SLACK_M = 3e-3
#: PyBullet's and the planner's shapes differ by up to this (test_planning_scene.py) [m].
HULL_TOLERANCE_M = 2.5e-3
#: Densely sampled timing: this many samples per second of motion.
TIMING_SAMPLES_PER_S = 20_000
#: A relative slack on the limits for floating point (the profiles reach them exactly).
LIMIT_SLACK = 1e-9


# -- timing ---------------------------------------------------------------------------------
def swap_plan(world: armfleet.World) -> Plan:
    """The two-arm swap: a path of several short segments (acceleration and jerk bind)."""
    plan = world.plan(swap_goals(world))
    assert len(plan.waypoints) >= 3, plan  # a multi-segment path, or the test is idle
    return plan


def long_turn_plan(world: armfleet.World) -> Plan:
    """bob turning away from the table by 2.5 rad: one long segment (velocity binds)."""
    bob = world.arm("bob")
    return bob.plan(bob.positions - np.array([2.5, 0, 0, 0, 0, 0, 0]))


@pytest.mark.parametrize(
    "make",
    [
        pytest.param(swap_plan, id="two-arm swap, several segments"),
        pytest.param(long_turn_plan, id="one long segment"),
    ],
)
def test_a_timed_path_keeps_every_joint_limit_and_its_straight_segments(
    make: Callable[[armfleet.World], Plan],
) -> None:
    """The rest-to-rest reference timing of a plan's waypoints (``TimedPath``; plans pass
    through their waypoints, tests/test_smooth_motion.py) sampled every 50 us: every
    joint's |v|, |a| and finite-difference jerk within the controller's limits (and the
    binding one reached, so the check has teeth), every sample on the straight segment
    between the waypoints it lies between, at rest at each waypoint; the plan's own
    timing takes no longer."""
    with shared_cell() as world:
        plan = make(world)
        arms = [world.arm(name) for name in plan.arms]
        velocity = np.concatenate([arm.position_controller.max_velocity for arm in arms])
        acceleration = np.concatenate(
            [
                np.full(7, float(arm.position_controller.parameters["max_acceleration_rad_s2"]))
                for arm in arms
            ]
        )
        jerk = np.concatenate(
            [
                np.full(7, float(arm.position_controller.parameters["max_jerk_rad_s3"]))
                for arm in arms
            ]
        )
        timing = TimedPath(plan.waypoints, JointLimits(velocity, acceleration, jerk))
        step = 1.0 / TIMING_SAMPLES_PER_S
        times = np.arange(0.0, timing.duration, step)
        position, speed, accel = timing.at(times)
        # The jerk is piecewise constant: the difference quotient of the acceleration over
        # one step is bounded by it exactly (plus rounding of a ~1e-9 difference / 5e-5).
        finite_jerk = np.abs(np.diff(accel, axis=0)) / step
        peaks = {
            "velocity": float((np.abs(speed) / velocity).max()),
            "acceleration": float((np.abs(accel) / acceleration).max()),
            "jerk": float((finite_jerk / jerk).max()),
        }
        assert peaks["velocity"] <= 1 + LIMIT_SLACK, peaks
        assert peaks["acceleration"] <= 1 + LIMIT_SLACK, peaks
        assert peaks["jerk"] <= 1 + 1e-6, peaks
        binding = "velocity" if make is long_turn_plan else "acceleration"
        assert peaks[binding] > 0.99 and peaks["jerk"] > 0.99, peaks
        # The velocity is the derivative of the position (the profile is what it says).
        np.testing.assert_allclose(
            np.diff(position, axis=0) / step, (speed[1:] + speed[:-1]) / 2, atol=1e-3
        )
        waypoints, arrivals = plan.waypoints, timing.times
        for index, (a, b) in enumerate(itertools.pairwise(waypoints)):
            inside = (times >= arrivals[index]) & (times <= arrivals[index + 1])
            rows = position[inside]
            fraction = (rows - a) @ (b - a) / float((b - a) @ (b - a))
            on_line = a + fraction[:, None] * (b - a)
            assert np.abs(rows - on_line).max() < 1e-9
            assert fraction.min() >= -1e-12 and fraction.max() <= 1 + 1e-12
            end = timing.at(np.array([arrivals[index + 1]]))
            np.testing.assert_allclose(end[0][0], b, atol=1e-12)
            assert np.abs(end[1]).max() < 1e-9  # at rest at every waypoint
        assert plan.timing.duration == pytest.approx(plan.duration_s - plan.start_delay_s)
        assert plan.timing.duration <= timing.duration + 1e-9


# -- the two-arm swap -----------------------------------------------------------------------
def test_a_swap_whose_straight_motion_hits_the_post_is_planned_around_it() -> None:
    """Straight ``move_together`` of the swap touches the post and stops both arms (run
    first, in its own world); planned jointly it is done with no contact and no stop,
    both arms start on the same step and stop on the same step, and end at their goals."""
    with shared_cell() as straight:
        goals = swap_goals(straight)
        watch = Watch(straight)
        straight.move_together(goals)
        watch.run(2.0)
        touched = {pair for _, pair, _ in watch.contacts}
        assert any("post" in pair for pair in touched), touched
        assert watch.stops >= 1
    with shared_cell() as world:
        bob, toby = world.arm("bob"), world.arm("toby")
        starts = {"bob": bob.positions, "toby": toby.positions}
        plan = world.plan(goals)
        watch = Watch(world)
        nearest = {"bob": math.inf, "toby": math.inf}
        ids = body_ids(world)

        def on_step(w: armfleet.World) -> None:
            watch(w)
            for name in nearest:
                nearest[name] = min(nearest[name], gap(w, name, "post", ids=ids))

        duration = world.execute(plan)
        world.run(duration + 0.3, on_step=on_step)
        assert watch.contacts == [] and watch.stops == 0
        # PyBullet saw both arms keep the clearance from the post, less the hull slack.
        assert min(nearest.values()) >= plan.clearance_m - CLEARANCE_SLACK_M, nearest
        starts_at = {name: watch.first_step_leaving(name, starts[name]) for name in starts}
        stops_at = {name: watch.last_step_moving(name) for name in starts}
        assert starts_at["bob"] == starts_at["toby"] == 0, starts_at
        assert stops_at["bob"] == stops_at["toby"], stops_at
        assert stops_at["bob"] == pytest.approx(duration / world.dt, abs=2)
        for name, arm in (("bob", bob), ("toby", toby)):
            assert np.abs(arm.positions - goals[name]).max() < ARRIVAL_RAD


# -- seeded problems across the table ---------------------------------------------------------
#: Obstacles of the shared cell an arm is measured against (besides the other arm).
CELL_OBSTACLES = ("table", "post", "wall_left", "wall_right")
#: Steps between two PyBullet distance measurements during a run (contacts: every step).
GAP_EVERY_STEPS = 5


def far_side_goals(
    world: armfleet.World, arms: tuple[str, ...], seed: int
) -> dict[str, FloatArray]:
    """Per arm, a joint goal with its tool pointing down over the far half of the table
    (past the post), drawn from ``seed``; drawn again until the request is not refused
    for its goal (in collision with the other arm's goal or the cell)."""
    rng = np.random.default_rng(seed)
    for _ in range(50):
        goals = {}
        for name in arms:
            arm = world.arm(name)
            base_x, toward = (0.0, 1.0) if name == "bob" else (0.9, -1.0)
            xyz = (
                base_x + toward * rng.uniform(0.5, 0.68),
                rng.uniform(-0.35, 0.35),
                rng.uniform(0.3, 0.55),
            )
            try:
                goals[name] = arm.solve_ik(tool_down(xyz, 0.0 if name == "bob" else math.pi))
            except armfleet.ArmfleetError:
                break
        else:
            try:
                world.plan(goals, timeout_s=0.001)
            except PlanningFailed as failure:
                if failure.reason is not FailureReason.GOAL_IN_COLLISION:
                    return goals
            else:
                return goals
    raise AssertionError(f"no clear far-side goals for {arms} from seed {seed}")


@pytest.mark.parametrize(
    ("arms", "seed"),
    [
        pytest.param(("bob",), 0, id="bob alone, seed 0"),
        pytest.param(("bob",), 2, id="bob alone, seed 2"),
        pytest.param(("bob", "toby"), 1, id="bob and toby jointly, seed 1"),
        pytest.param(("bob", "toby"), 5, id="bob and toby jointly, seed 5"),
    ],
)
def test_planned_motions_across_the_table_touch_nothing(arms: tuple[str, ...], seed: int) -> None:
    """Seeded goals over the far half of the table, planned and run: no contact on
    /collisions, no stop, PyBullet's distance from each arm to the table, post, walls
    and the other arm never under the clearance less the hull slack, goals reached."""
    with shared_cell() as world:
        goals = far_side_goals(world, arms, seed)
        plan = world.plan(goals)
        watch = Watch(world)
        ids = body_ids(world)
        others = {name: [*CELL_OBSTACLES, *(a for a in world.arms if a != name)] for name in arms}
        nearest = {name: math.inf for name in arms}

        def on_step(w: armfleet.World) -> None:
            watch(w)
            if len(watch.moving) % GAP_EVERY_STEPS == 0:
                for name in arms:
                    for other in others[name]:
                        nearest[name] = min(nearest[name], gap(w, name, other, ids=ids))

        world.run(world.execute(plan) + 0.3, on_step=on_step)
        assert watch.contacts == [] and watch.stops == 0
        assert min(nearest.values()) >= plan.clearance_m - CLEARANCE_SLACK_M, (plan, nearest)
        for name in arms:
            assert np.abs(world.arm(name).positions - goals[name]).max() < ARRIVAL_RAD


# -- refusals -------------------------------------------------------------------------------
#: How far inside the 10 mm clearance the refused starts and goals are [m]: 5 mm away from
#: the obstacle by PyBullet's distance (in the clearance, not touching).
INSIDE_GAP_M = 5e-3
BOB_AWAY = (0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # a clear goal: bob's joint 1 turned 0.3 rad


def goal_near_the_post(world: armfleet.World) -> FloatArray:
    """bob's joints with his hand 5 mm from the post (PyBullet's distance), found by
    bisection along x in a scratch copy of the cell."""
    with shared_cell() as scratch:
        bob = scratch.arm("bob")
        near, far = 0.40, 0.25  # tcp x [m]: into the post / well clear of it
        goal = bob.positions
        for _ in range(40):
            x = (near + far) / 2
            goal = bob.solve_ik(tool_down((x, 0.0, 0.42)), link="tcp")
            distance = gap_at(scratch, {"bob": goal}, "bob", "post")
            if abs(distance - INSIDE_GAP_M) < 2e-4:
                return goal
            near, far = (near, x) if distance > INSIDE_GAP_M else (x, far)
    raise AssertionError(f"no goal {INSIDE_GAP_M} m from the post (last: {distance} m)")


def start_near_a_box(world: armfleet.World) -> Callable[[], object]:
    """A static box put 5 mm under bob's fingertips; then a plan to a clear goal."""
    tip = min(link_gap(world, "bob", f"bob_panda_{s}finger", "ground") for s in ("left", "right"))
    hand = world.tf.lookup("world", "bob_tcp")[:3, 3]
    world.add_object(
        "block",
        "box",
        size=(0.04, 0.04, 0.04),
        mass=0.0,
        at=(hand[0], hand[1], tip - INSIDE_GAP_M - 0.02),
    )
    assert gap(world, "bob", "block") == pytest.approx(INSIDE_GAP_M, abs=1e-3)
    bob = world.arm("bob")
    return lambda: bob.move_to(bob.positions + np.array(BOB_AWAY), avoid_collisions=True)


def goal_near_post(world: armfleet.World) -> Callable[[], object]:
    goal = goal_near_the_post(world)
    return lambda: world.arm("bob").move_to(goal, avoid_collisions=True)


def pose_out_of_reach(world: armfleet.World) -> Callable[[], object]:
    return lambda: world.arm("bob").move_to_pose(tool_down((2.0, 0.0, 0.5)), avoid_collisions=True)


def swap_in_one_millisecond(world: armfleet.World) -> Callable[[], object]:
    goals = swap_goals(world)
    return lambda: world.move_together(goals, avoid_collisions=True, timeout_s=0.001)


@pytest.mark.parametrize(
    ("make", "reason", "named"),
    [
        pytest.param(
            start_near_a_box,
            FailureReason.START_IN_COLLISION,
            ("bob_panda_", "block"),
            id="start 5 mm from a box (clearance 10 mm) -> start in collision, both named",
        ),
        pytest.param(
            goal_near_post,
            FailureReason.GOAL_IN_COLLISION,
            ("bob_panda_", "post"),
            id="goal 5 mm from the post -> goal in collision, hand and post named",
        ),
        pytest.param(
            pose_out_of_reach,
            FailureReason.GOAL_UNREACHABLE,
            (),
            id="pose 2 m away -> goal unreachable",
        ),
        pytest.param(
            swap_in_one_millisecond,
            FailureReason.NO_PATH,
            (),
            id="the swap in 1 ms -> no path found, samples given",
        ),
    ],
)
def test_a_refused_plan_is_one_line_and_nothing_moves(
    make: Callable[[armfleet.World], Callable[[], object]],
    reason: FailureReason,
    named: tuple[str, ...],
) -> None:
    with shared_cell() as world:
        attempt = make(world)
        world.run(0.2)  # settle whatever the set-up added
        arms = [world.arm("bob"), world.arm("toby")]
        sent: list[object] = []
        for arm in arms:
            world.bus.subscribe(f"/{arm.name}/position_controller/commands", sent.append)
            world.bus.subscribe(f"/{arm.name}/planned_motion", sent.append)
        before = [arm.positions for arm in arms]
        with pytest.raises(PlanningFailed) as failure:
            attempt()
        error = failure.value
        message = str(error)
        assert "\n" not in message and error.reason is reason, message
        assert reason.value in message
        if named:
            assert len(error.links) == 2, message
            for part in named:
                assert any(part in link for link in error.links), (part, error.links)
                assert part in message
            # The distance it states is PyBullet's, within the hulls' difference.
            stated = float(message.split(" is ")[1].split(" mm from ")[0]) / 1000
            assert stated == pytest.approx(INSIDE_GAP_M, abs=HULL_TOLERANCE_M), message
        if reason is FailureReason.NO_PATH:
            assert "samples tried" in message and error.samples >= 0
        world.run(0.2)
        assert sent == []
        for arm, old in zip(arms, before, strict=True):
            assert not arm.is_moving
            assert np.abs(arm.positions - old).max() < HOLD_DRIFT_RAD


def test_a_goal_in_collision_states_the_depth_pybullet_sees() -> None:
    """bob's fingertips 5 mm into the floor (PyBullet) at the goal: the refusal says the
    finger touches the floor, not that it is some mm away."""
    with armfleet.World() as world, armfleet.World() as scratch:
        bob = world.spawn("bob")
        scratch.spawn("bob")
        pose = np.diag([1.0, -1.0, -1.0, 1.0])
        pose[:3, 3] = (0.5, 0.0, 0.0)
        low, high = -0.02, 0.03  # tcp heights [m]: deep in the floor / above it
        goal, depth = bob.positions, 0.0
        for _ in range(40):  # the base stands 1 mm in the floor: below -1 mm it is a finger
            pose[2, 3] = (low + high) / 2
            goal = bob.solve_ik(pose, link="tcp")
            depth = gap_at(scratch, {"bob": goal}, "bob", "ground")
            if abs(depth + INSIDE_GAP_M) < 2e-4:
                break
            low, high = (pose[2, 3], high) if depth < -INSIDE_GAP_M else (low, pose[2, 3])
        assert depth == pytest.approx(-INSIDE_GAP_M, abs=2e-4)
        with pytest.raises(PlanningFailed) as failure:
            bob.plan(goal)
        assert failure.value.reason is FailureReason.GOAL_IN_COLLISION
        assert "finger" in str(failure.value) and "ground" in str(failure.value)
        assert "touches ground" in str(failure.value), str(failure.value)


# -- a held box -----------------------------------------------------------------------------
#: The held box's pose in the hand may change by this much while it is carried [m]
#: (it sits in the fingers by friction; 0.5 mm was seen).
IN_HAND_DRIFT_M = 2e-3


def test_a_box_held_by_bob_is_carried_around_a_post_without_touching_it() -> None:
    """bob picks a 4 cm box from a table (straight down and up: a start within the
    clearance of the table is refused by design), then carries it to the other side of
    a post standing on the straight tool line: no contact of the box or the arm with
    the post or anything else (the box in its fingers excepted), PyBullet's distance
    from the box to the post never under the clearance less the hull slack, and the box
    stays where it was in the hand."""
    with armfleet.World() as world:
        bob = world.spawn("bob")
        world.add_object("table", "box", size=(0.4, 0.8, 0.2), at=(0.5, 0.0, 0.1), mass=0.0)
        world.add_object("post", "cylinder", size=(0.03, 0.5), at=(0.45, 0.0, 0.45), mass=0.0)
        world.add_object("block", "box", size=(0.04, 0.04, 0.04), at=(0.45, -0.2, 0.22), mass=0.1)
        bob.gripper.open()
        world.run(0.3)
        above, goal_xyz = (0.45, -0.2, 0.30), (0.45, 0.2, 0.30)
        world.run(bob.move_to_pose(tool_down(above), link="tcp", avoid_collisions=True) + 0.2)
        world.run(bob.move_to_pose(tool_down((0.45, -0.2, 0.22)), link="tcp", linear=True) + 0.2)
        bob.gripper.close()
        world.run(0.5)
        assert bob.gripper.holding
        world.run(bob.move_to_pose(tool_down(above), link="tcp", linear=True) + 0.2)
        # The post stands on the straight tool line from here to the goal: the line
        # (along y at x = 0.45) passes through its axis.
        assert world.object("post").position[0] == pytest.approx(above[0])
        fingers = {"bob_panda_leftfinger", "bob_panda_rightfinger"}
        watch = Watch(world, allowed={tuple(sorted((f, "block"))) for f in fingers})  # type: ignore[misc]
        in_hand = np.linalg.solve(
            world.tf.lookup("world", "bob_tcp"), world.tf.lookup("world", "block")
        )
        drift, nearest = 0.0, math.inf
        ids = body_ids(world)

        def on_step(w: armfleet.World) -> None:
            nonlocal drift, nearest
            watch(w)
            now = np.linalg.solve(w.tf.lookup("world", "bob_tcp"), w.tf.lookup("world", "block"))
            drift = max(drift, float(np.linalg.norm(now[:3, 3] - in_hand[:3, 3])))
            nearest = min(nearest, gap(w, "block", "post", ids=ids), gap(w, "bob", "post", ids=ids))

        duration = bob.move_to_pose(tool_down(goal_xyz), link="tcp", avoid_collisions=True)
        world.run(duration + 0.3, on_step=on_step)
        assert watch.contacts == [] and watch.stops == 0
        assert nearest >= 0.01 - CLEARANCE_SLACK_M, nearest
        assert drift < IN_HAND_DRIFT_M and bob.gripper.holding
        reached = world.tf.lookup("world", "bob_tcp")[:3, 3]
        assert np.linalg.norm(reached - goal_xyz) < 1e-3
        assert np.linalg.norm(world.object("block").position[:2] - goal_xyz[:2]) < 5e-3


# -- re-targeting, protective stops, a stale plan, recording ---------------------------------
def bob_goal_across(world: armfleet.World) -> FloatArray:
    """bob's tool over toby's side of the table, past the post (a planned path)."""
    return world.arm("bob").solve_ik(tool_down((0.55, 0.25, 0.45)))


def test_a_plain_move_to_takes_over_a_planned_motion_smoothly() -> None:
    """Half-way through a planned motion, at full speed, a plain move_to back to the start
    takes over at once: the reference stays within the velocity and acceleration limits
    across the switch (no jump), no fault or stop, and bob ends at the new target.

    The planned motion is bob's long turn, one straight segment, so the straight way back
    retraces it and cannot touch anything (a straight move from the middle of a path
    around the post may hit the post: that is a stop, not a failed take-over)."""
    with shared_cell() as world:
        bob = world.arm("bob")
        start = bob.positions
        plan = long_turn_plan(world)
        duration = world.execute(plan)
        watch = Watch(world)
        watch.run(duration / 2)
        trajectory = bob.position_controller.trajectory
        assert trajectory is not None and bob.is_moving
        assert np.abs(trajectory.velocity).max() > 0.9 * bob.position_controller.max_velocity[0]
        bob.move_to(start)
        for _ in range(200):  # at most 10 s of simulated time
            watch.run(0.05)
            if not bob.is_moving:
                break
        assert not bob.is_moving
        assert watch.contacts == [] and watch.stops == 0
        controller = bob.position_controller
        assert bob.controller_manager.fault is None and controller.stop_reason is None
        reference = np.array([refs["bob"] for refs in watch.references])
        velocity = np.diff(reference, axis=0) / world.dt
        limit_v = controller.max_velocity
        limit_a = float(controller.parameters["max_acceleration_rad_s2"])
        assert np.all(np.abs(velocity) <= limit_v * (1 + 1e-6))
        # Reference velocities are differences of positions: their differences are
        # bounded by the acceleration limit (1 % for the one-step differencing).
        assert np.all(np.abs(np.diff(velocity, axis=0)) / world.dt <= limit_a * 1.01)
        assert np.abs(bob.positions - start).max() < ARRIVAL_RAD


def box_on_the_path(world: armfleet.World, fraction: float) -> None:
    """A static 12 cm box where bob's tool0 will be ``fraction`` of the way along his
    current motion (from the reference he follows). ``add_object`` refuses a box in a
    moving arm's path, so it is added out of reach and teleported there (``set_pose``
    checks where the arms are, not where they go)."""
    bob = world.arm("bob")
    trajectory = bob.position_controller.trajectory
    assert trajectory is not None
    rows = trajectory.remaining_positions(bob.position_controller.period)
    ahead = tool_position(bob, rows[int(fraction * (len(rows) - 1))])
    box = world.add_object("obstacle", "box", size=(0.12, 0.12, 0.12), at=(0, 0, 5), mass=0.0)
    box.set_pose(tuple(ahead))


def test_a_planned_motion_still_stops_on_contact() -> None:
    """A static box dropped on the path of a running planned motion: bob touches it, is
    stopped (protective stop), holds there and does not reach the goal."""
    with shared_cell() as world:
        bob = world.arm("bob")
        goal = bob_goal_across(world)
        duration = bob.move_to(goal, avoid_collisions=True)
        world.run(0.05)
        box_on_the_path(world, 0.6)
        watch = Watch(world)
        watch.run(duration)
        assert watch.stops == 1 and bob.position_controller.stop_reason is not None
        assert any("obstacle" in pair for _, pair, _ in watch.contacts)
        held = bob.positions
        world.run(0.2)
        assert np.abs(bob.positions - held).max() < HOLD_DRIFT_RAD and not bob.is_moving
        assert np.abs(bob.positions - goal).max() > 0.1


def test_a_plan_made_before_the_world_changed_is_refused() -> None:
    """A plan, then a box put on its path: executing the plan later is refused (the
    world changed; plan again) and nothing moves."""
    with shared_cell() as world:
        bob = world.arm("bob")
        plan = bob.plan(bob_goal_across(world))
        samples = plan.timing.sample(bob.position_controller.period).position
        ahead = tool_position(bob, samples[len(samples) // 2])
        world.add_object("obstacle", "box", size=(0.12, 0.12, 0.12), at=tuple(ahead), mass=0.0)
        world.step()
        before = bob.positions
        with pytest.raises(armfleet.ArmfleetError, match="no longer clear") as refused:
            world.execute(plan)
        assert "\n" not in str(refused.value) and "obstacle" in str(refused.value)
        world.run(0.2)
        assert not bob.is_moving and np.abs(bob.positions - before).max() < HOLD_DRIFT_RAD


def test_a_planned_motion_is_recorded(tmp_path: Path) -> None:
    """The announcement of a planned move is in the MCAP recording (armfleet's reader):
    one /bob/planned_motion message, with bob's joints and the plan's waypoints."""
    path = tmp_path / "planned.mcap"
    with shared_cell() as world:
        bob = world.arm("bob")
        recorder = armfleet.record(world, path, topics=["/bob/planned_motion"])
        plan = bob.plan(bob_goal_across(world))
        world.run(world.execute(plan) + 0.1)
        recorder.stop()
    messages = list(open_recording(path).messages(["/bob/planned_motion"]))
    assert len(messages) == 1
    trajectory = messages[0].data["trajectory"]
    assert tuple(trajectory["joint_names"]) == bob.joint_names
    recorded = np.array([point["positions"] for point in trajectory["points"]])
    np.testing.assert_allclose(recorded, plan.waypoints, atol=1e-12)
