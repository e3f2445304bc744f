"""Continuous joints, end to end: example-robot-data's Jaco (Kinova), whose joints 1, 4 and
6 are continuous, loaded by path with no wrapper (armfleet/kinematics/continuous_joints.py).

What is checked is what PyBullet simulates and the bus reports: the measured angles, the
broadcast joint states, the frames and the contacts; a continuous joint's angle is its
true one, never wrapped, and a choice between equivalent angles takes the nearest.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.errors import JointLimitError
from armfleet.messages import FloatArray, JointState
from armfleet.recording import open_recording
from armfleet.scenarios.reach_targets import draw_targets
from tests.test_own_robot import (
    MOVE_RAD,
    POSE_TOLERANCE,
    ROBOTS,
    TRACKING_RAD,
    _box_link,
    _two_copies,
    _write,
)

JACO = ROBOTS / "kinova_description/robots/kinova.urdf"
#: The Jaco's continuous joints (indices into its arm joints): 1, 4 and 6.
CONTINUOUS = (0, 3, 5)
#: An IK solution lands on the pose it was asked for within this [m, rad].
IK_TOLERANCE = 1e-5


@pytest.fixture(scope="module")
def jaco() -> Iterator[armfleet.World]:
    """bob and toby, two Jacos (toby 2 m away, facing bob); spawned once, as each spawn of
    a new world searches the model's clear home and samples its self-contacts again."""
    with _two_copies(str(JACO)) as world:
        yield world


def _settle(world: armfleet.World, arm: armfleet.Arm) -> None:
    while arm.is_moving:
        world.run(0.1)
    world.run(0.2)


def _go(world: armfleet.World, arm: armfleet.Arm, target: FloatArray) -> None:
    arm.move_to(target)
    _settle(world, arm)
    assert np.abs(arm.positions - target).max() < TRACKING_RAD


def _plan_to(world: armfleet.World, arm: armfleet.Arm, target: FloatArray) -> None:
    """A planned move to ``target`` (its continuous joints already the nearest turn)."""
    arm.move_to(target, avoid_collisions=True, timeout_s=10.0)
    _settle(world, arm)
    assert np.abs(arm.positions - target).max() < TRACKING_RAD


def _frames_agree(world: armfleet.World, arm: armfleet.Arm) -> None:
    """Every simulated link's world pose: PyBullet's, Pinocchio's and TF's agree."""
    arm.kinematics.update(arm.body.position)
    for link in arm.body.link_names:
        from_bullet = arm.body.link_world_pose(link)
        from_pinocchio = arm.kinematics.world_pose(link)
        from_tf = world.tf.lookup("world", link)
        assert np.abs(from_bullet - from_pinocchio).max() < POSE_TOLERANCE, link
        assert np.abs(from_tf - from_pinocchio).max() < POSE_TOLERANCE, link


def test_the_jaco_comes_up_twice_prefixed_with_unbounded_continuous_joints(
    jaco: armfleet.World,
) -> None:
    for arm in jaco.arms.values():
        assert all(name.startswith(f"{arm.name}_") for name in arm.joint_names)
        assert all(link.startswith(f"{arm.name}_") for link in arm.body.link_names)
        lower, upper = arm.joint_limits
        unbounded = np.isinf(lower) & np.isinf(upper)
        assert np.flatnonzero(unbounded).tolist() == list(CONTINUOUS)
        assert np.all(np.isfinite(arm.kinematics.velocity_limit))  # as the file gives them
        assert np.all(np.isfinite(arm.kinematics.effort_limit))
        # One position per joint, as PyBullet has it.
        assert arm.kinematics.model.nq == arm.kinematics.model.nv == len(arm.body.position)


def test_every_jaco_joint_tracks_a_short_move_and_its_frames_agree(jaco: armfleet.World) -> None:
    bob = jaco.arm("bob")
    _, upper = bob.joint_limits
    home = np.asarray(bob.positions)
    target = np.where(home + MOVE_RAD <= upper, home + MOVE_RAD, home - MOVE_RAD)
    bob.move_to(target)
    jaco.run(0.2)
    assert bob.is_moving
    _frames_agree(jaco, bob)  # mid-motion
    _settle(jaco, bob)
    assert np.abs(bob.positions - target).max() < TRACKING_RAD
    assert bob.mode is armfleet.ArmMode.HOLDING
    _go(jaco, bob, home)


def test_a_continuous_joint_turns_past_pi_and_past_a_turn_unwrapped(
    jaco: armfleet.World, tmp_path: Path
) -> None:
    bob = jaco.arm("bob")
    home = np.asarray(bob.positions)
    path = tmp_path / "turns.mcap"
    with armfleet.record(jaco, path, topics=["/bob/joint_states"]):
        for angle in (4.0, 7.0):  # past pi, then past a whole turn (7.0 = 2 pi + 0.72)
            target = home.copy()
            target[0] = angle
            _go(jaco, bob, target)
            state = bob.joint_state  # the broadcaster's latest /bob/joint_states
            column = state.name.index(bob.joint_names[0])
            assert abs(state.position[column] - angle) < TRACKING_RAD
            _frames_agree(jaco, bob)
    recorded = [
        message.data["position"][message.data["name"].index(bob.joint_names[0])]
        for message in open_recording(path).messages(["/bob/joint_states"])
    ]
    assert abs(recorded[-1] - 7.0) < TRACKING_RAD  # the true angle, not 7.0 - 2 pi
    assert np.all(np.diff(recorded) > -1e-6)  # it turned one way, no jump back a turn
    # The reference holds it there: no drift back to a wrapped angle.
    jaco.run(0.5)
    assert abs(bob.positions[0] - 7.0) < TRACKING_RAD
    # A start a turn past home (the same pose) is taken as given, as a target is.
    start = home.copy()
    start[3] += 2 * math.pi
    ned = jaco.spawn("ned", model=str(JACO), at=(0.0, 2.0), initial_positions=start)
    try:
        assert abs(ned.positions[3] - start[3]) < TRACKING_RAD
    finally:
        jaco.remove("ned")
    _go(jaco, bob, home)


def test_ik_gives_a_continuous_joint_the_angle_nearest_the_present_one(
    jaco: armfleet.World,
) -> None:
    bob = jaco.arm("bob")
    home = np.asarray(bob.positions)
    stretched = home.copy()
    stretched[[1, 2]] = math.pi  # upright: the wrist turns clear of the arm (not at home)
    _plan_to(jaco, bob, stretched)
    here = stretched.copy()
    here[list(CONTINUOUS)] += 2 * math.pi  # a turn on: the same pose, other angles
    _go(jaco, bob, here)
    there = here + 0.12
    _go(jaco, bob, there)
    goal = jaco.tf.lookup("world", "bob_tool0")  # the pose the arm showed there
    _go(jaco, bob, here)
    solution = bob.solve_ik(goal)
    # The nearest solution is where the arm was: the continuous joints a turn on, not
    # wrapped back to the home's turn (2 pi away) nor drifted.
    assert np.abs(solution - there).max() < 1e-4
    bob.move_to_pose(goal)
    _settle(jaco, bob)
    assert np.abs(bob.positions - there).max() < TRACKING_RAD
    reached = jaco.tf.lookup("world", "bob_tool0")
    assert np.abs(reached[:3, 3] - goal[:3, 3]).max() < 1e-3
    # A seed a turn back gives the solution a turn back.
    seed = here.copy()
    seed[list(CONTINUOUS)] -= 2 * math.pi
    back = bob.solve_ik(goal, seed=seed)
    expected = there.copy()
    expected[list(CONTINUOUS)] -= 2 * math.pi
    assert np.abs(back - expected).max() < 1e-4
    _go(jaco, bob, stretched)
    _plan_to(jaco, bob, home)


def test_a_planned_move_of_a_continuous_joint_takes_the_short_way_round(
    jaco: armfleet.World,
) -> None:
    bob = jaco.arm("bob")
    home = np.asarray(bob.positions)
    start = home.copy()
    start[0] = 3.0
    _go(jaco, bob, start)
    goal = start.copy()
    goal[0] = -3.0  # 6 rad back the long way; 0.28 rad on through pi
    plan = bob.plan(goal)
    path = plan.waypoints[:, 0]
    short_end = 2 * math.pi - 3.0
    assert abs(path[-1] - short_end) < 1e-9
    assert np.all((path >= 3.0 - 1e-9) & (path <= short_end + 1e-9)), path
    assert np.abs(np.diff(path)).sum() < 0.5
    measured: list[float] = []

    def on_state(message: JointState) -> None:
        measured.append(float(message.position[message.name.index(bob.joint_names[0])]))

    subscription = jaco.bus.subscribe("/bob/joint_states", on_state)
    contacts_before = jaco.contacts.total_contacts
    try:
        jaco.execute(plan)
        _settle(jaco, bob)
    finally:
        subscription.cancel()
    # As measured: through pi, a short travel, at the angle equivalent to -3.0.
    assert max(measured) > math.pi > min(measured)
    assert np.abs(np.diff(measured)).sum() < 0.5
    assert abs(bob.positions[0] - short_end) < TRACKING_RAD
    assert math.cos(bob.positions[0]) == pytest.approx(math.cos(-3.0), abs=TRACKING_RAD)
    assert math.sin(bob.positions[0]) == pytest.approx(math.sin(-3.0), abs=TRACKING_RAD)
    assert np.abs(bob.positions[1:] - start[1:]).max() < TRACKING_RAD
    assert jaco.contacts.total_contacts == contacts_before
    _go(jaco, bob, home)


@pytest.mark.parametrize(
    "avoid_collisions",
    [pytest.param(False, id="a direct move"), pytest.param(True, id="a planned move")],
)
def test_a_revolute_joints_target_past_its_limit_is_still_refused_in_one_line(
    jaco: armfleet.World, avoid_collisions: bool
) -> None:
    bob = jaco.arm("bob")
    before = np.asarray(bob.positions)
    _, upper = bob.joint_limits
    target = before.copy()
    target[1] = upper[1] + 0.5  # joint 2: revolute, limited
    with pytest.raises(JointLimitError) as caught:
        bob.move_to(target, avoid_collisions=avoid_collisions)
    message = str(caught.value)
    assert bob.joint_names[1] in message and "\n" not in message, message
    jaco.run(0.2)
    assert np.abs(bob.positions - before).max() < TRACKING_RAD


def test_a_continuous_joint_without_a_limit_element_turns_on(tmp_path: Path) -> None:
    """URDF lets a continuous joint leave out ``<limit>`` (no effort or velocity limit):
    it moves at the controller's acceleration and jerk limits, past a turn."""
    box = "0.06 0.06 0.3"
    urdf = _write(
        tmp_path / "spinner.urdf",
        f"""
        <robot name="spinner">{_box_link("base", "0.2 0.2 0.1", 3.0, "0 0 0.05")}
          {_box_link("link1", box, 1.0, "0 0 0.15")}{_box_link("link2", box, 1.0, "0 0 0.15")}
          <joint name="spin" type="continuous">
            <parent link="base"/><child link="link1"/><origin xyz="0 0 0.1"/>
            <axis xyz="0 0 1"/>
          </joint>
          <joint name="tilt" type="revolute">
            <parent link="link1"/><child link="link2"/><origin xyz="0 0 0.3"/>
            <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="50" velocity="2"/>
          </joint>
        </robot>
        """,
    )
    with armfleet.World() as world:
        bob = world.spawn("bob", model=str(urdf), at=(0.0, 0.0))
        lower, upper = bob.joint_limits
        assert lower[0] == -math.inf and upper[0] == math.inf
        assert (lower[1], upper[1]) == (-2.0, 2.0)
        target = np.array([2 * math.pi + 1.0, 0.5])
        _go(world, bob, target)
        _frames_agree(world, bob)


def test_reach_targets_and_joint_actions_of_a_jaco_stay_within_a_turn(
    jaco: armfleet.World,
) -> None:
    """The Reach task draws a continuous joint's target angle from one turn, [-pi, pi]
    (from -inf..inf it drew NaN), and absolute joint actions are bounded the same way.
    (Gymnasium's checker runs an environment of a vendor file in
    tests/test_own_robot_surfaces.py; here only what continuous joints change.)"""
    gymnasium = pytest.importorskip("gymnasium")
    from armfleet.envs.actions import ActionKind, StepLimits, arm_action_space

    bob = jaco.arm("bob")
    continuous = bob.kinematics.continuous[bob.kinematics.arm_indices]
    assert continuous.sum() == 3
    box = arm_action_space(bob, ActionKind.JOINT_POSITIONS, StepLimits())
    positions = box[ActionKind.JOINT_POSITIONS.value]
    assert isinstance(positions, gymnasium.spaces.Box)
    assert np.all(positions.low[continuous] == np.float32(-np.pi))
    assert np.all(positions.high[continuous] == np.float32(np.pi))
    assert np.all(np.isfinite(positions.low)) and np.all(np.isfinite(positions.high))
    for target in draw_targets(bob, np.random.default_rng(5), 5):
        drawn = target.positions
        assert np.all(np.isfinite(drawn)) and np.all(np.abs(drawn[continuous]) <= np.pi)
