"""Trajectory tracking: bob follows jerk-limited motions; toby, commanded nothing, stays put.

Tolerances: max |q_ref - q| during motion < 1e-5 rad (issue #2 asked 1e-3; measured
3.2e-6 on the Panda, most of it the settling of its brake release just before the
move, and 3.3e-7 on the UR5, since the controller accounts for PyBullet's integrator
and Bullet's link damping is off, issue #14); final error < 1e-7 rad 0.2 s after the
reference ends (measured 7e-10); measured joint velocities never above the URDF
limits; toby's joints move < 1e-5 rad. And on the benchmark's move armfleet tracks
at least as well as PyBullet's own POSITION_CONTROL given Ruckig's velocities.

Each motion is recorded (MCAP); a failing test leaves the recording and its
tracking plots in ``test-artifacts/<test id>/`` (see ``keep_on_failure``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.controllers.jerk_limited_trajectory import JerkLimitedTrajectory
from armfleet.messages import ControllerState, JointState

MAX_TRACKING_ERROR_RAD = 1e-5
FINAL_ERROR_RAD = 1e-7
SETTLE_S = 0.2
BYSTANDER_MOTION_RAD = 1e-5
#: What a failing test's recording holds: enough to plot and replay the motion.
RECORDED_TOPICS = [
    "/bringup",
    "/tf_static",
    *(f"/{arm}/{topic}" for arm in ("bob", "toby") for topic in ("joint_states", "status")),
    "/bob/position_controller/state",
    "/bob/position_controller/commands",
]


@dataclass
class Recording:
    states: list[ControllerState] = field(default_factory=list)
    bystander: list[JointState] = field(default_factory=list)
    #: The motion as an MCAP file, for a person to look at if a test fails.
    mcap: Path | None = None

    def errors(self) -> np.ndarray:
        return np.array([s.reference_position - s.position for s in self.states])


def run_until_still(world: armfleet.World, arm: armfleet.Arm, limit_s: float = 10.0) -> None:
    deadline = world.time + limit_s
    while arm.is_moving:
        assert world.time < deadline, f"{arm.name} still moving after {limit_s} s"
        world.run(0.01)


@pytest.fixture(scope="module", params=["panda", "ur5"])
def tracked(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory):
    """bob and toby of one model at (0,0) and (1,0); bob through three targets, one mid-motion."""
    model = request.param
    world = armfleet.World()
    mcap = tmp_path_factory.mktemp("tracking") / f"tracking_{model}.mcap"
    recording = Recording(mcap=mcap)
    with armfleet.record(world, mcap, topics=RECORDED_TOPICS):
        bob = world.spawn("bob", model=model, at=(0, 0))
        toby = world.spawn("toby", model=model, at=(1, 0))
        world.bus.subscribe("/bob/position_controller/state", recording.states.append)
        world.bus.subscribe("/toby/joint_states", recording.bystander.append)

        home = bob.positions
        lower, upper = bob.joint_limits
        # Clear of the arm itself (at home - 0.5 a Panda's finger is 6.8 mm into its link1,
        # which move_to refuses, as spawn does), as is the way between them.
        targets = [home + 0.62, home - 0.4, home + 0.3]
        for target in targets:
            assert np.all((lower < target) & (target < upper)), "test targets must be reachable"

        bob.move_to(targets[0])
        run_until_still(world, bob)
        bob.move_to(targets[1])
        world.run(0.5)
        assert bob.is_moving, "the third target must arrive mid-motion"
        bob.move_to(targets[2])  # re-plan from the moving reference
        run_until_still(world, bob)
        motion_end = len(recording.states)
        world.run(SETTLE_S)
    yield model, world, bob, toby, recording, targets, motion_end
    world.close()


@pytest.fixture(autouse=True)
def keep_tracking_recording(
    request: pytest.FixtureRequest, keep_on_failure: Callable[[Path], None]
) -> None:
    """A failing test on ``tracked`` leaves its recording and plots in test-artifacts/."""
    if "tracked" in request.fixturenames:
        recording = request.getfixturevalue("tracked")[4]
        if recording.mcap is not None:
            keep_on_failure(recording.mcap)


def test_targets_span_at_least_one_radian_per_joint(tracked) -> None:
    *_, targets, _ = tracked
    span = np.ptp(np.array(targets), axis=0)
    assert np.all(span >= 1.0), span


def test_max_tracking_error_during_motion(tracked) -> None:
    model, _, _, _, recording, _, motion_end = tracked
    errors = recording.errors()[:motion_end]
    worst = np.abs(errors).max()
    print(f"{model}: max {worst:.3e} rad, rms {np.sqrt(np.mean(errors**2)):.3e} rad")
    assert worst < MAX_TRACKING_ERROR_RAD


def test_final_error_after_settling(tracked) -> None:
    model, _, bob, _, _, targets, _ = tracked
    final = np.abs(bob.positions - targets[-1]).max()
    print(f"{model}: final {final:.3e} rad")
    assert final < FINAL_ERROR_RAD


def test_velocities_within_urdf_limits(tracked) -> None:
    _, _, bob, _, recording, _, _ = tracked
    limits = bob.kinematics.velocity_limit[bob.kinematics.arm_indices]
    velocities = np.array([s.velocity for s in recording.states])
    assert np.all(np.abs(velocities) <= limits), np.abs(velocities).max(axis=0) / limits


@pytest.mark.parametrize("model", ["panda", "ur5"])
def test_velocity_limit_holds_on_a_long_move(
    model: str, tmp_path: Path, keep_on_failure: Callable[[Path], None]
) -> None:
    """A 2.5 rad move of every joint is long enough to cruise at the velocity limit.

    The arm stands on a 1.2 m pedestal so that such a sweep clears the floor. The UR5's
    shoulder lift, elbow and first wrist joint move 0.5 rad only: swept 2.5 rad they fold
    the arm onto itself (upper arm against the base, the wrist against the forearm), a
    self-contact that stops the arm since contact pairs are sampled (the UR5 SRDF had
    ruled those pairs out); its pan and last two joints still sweep 2.5 rad.
    """
    mcap = tmp_path / f"long_move_{model}.mcap"
    keep_on_failure(mcap)
    topics = ["/bringup", "/tf_static", "/bob/joint_states", "/bob/position_controller/state"]
    with armfleet.World() as world, armfleet.record(world, mcap, topics=topics):
        arm = world.spawn("bob", model=model, at=(0, 0, 1.2))
        lower, upper = arm.joint_limits
        start = arm.positions
        # Go 2.5 rad (or as far as the limits allow) towards the roomier side.
        roomier = np.where(upper - start > start - lower, 1.0, -1.0)
        room = np.where(roomier > 0, upper - start, start - lower) - 0.05
        target = start + roomier * np.minimum(2.5, room)
        if model == "ur5":
            target[1:4] = start[1:4] + roomier[1:4] * 0.5
        states: list[JointState] = []
        world.bus.subscribe("/bob/joint_states", states.append)
        arm.move_to(target)
        run_until_still(world, arm)
        limits = arm.kinematics.velocity_limit
        ratio = np.abs(np.array([s.velocity for s in states])).max(axis=0) / limits
        assert np.all(ratio <= 1.0), ratio
        # Ruckig synchronises the joints; the one that limits the motion cruises
        # at the scaled limit (0.95 of the URDF's by default).
        assert ratio[arm.kinematics.arm_indices].max() > 0.9, ratio


def test_reference_is_jerk_limited(tracked) -> None:
    _, world, bob, _, recording, _, _ = tracked
    limit = bob.position_controller.parameters["max_jerk_rad_s3"]
    accelerations = np.array([s.reference_acceleration for s in recording.states])
    jerk = np.diff(accelerations, axis=0) / world.dt
    assert np.abs(jerk).max() <= limit * (1 + 1e-6)


def test_bystander_does_not_move(tracked) -> None:
    _, _, _, _, recording, _, _ = tracked
    positions = np.array([s.position for s in recording.bystander])
    assert len(positions) > 1000
    assert np.abs(positions - positions[0]).max() < BYSTANDER_MOTION_RAD


def test_retarget_that_would_overshoot_a_limit_is_refused(world: armfleet.World) -> None:
    """A re-plan whose braking would carry a joint past its limit is refused.

    With the shipped limits a time-optimal re-plan brakes within the old plan's
    envelope, so the case is built by moving the controller's lower limit of
    joint 1 to just ahead of the arm while it rushes that way.
    """
    bob = world.spawn("bob")
    target = bob.positions.copy()
    target[0] -= 1.5
    bob.move_to(target)
    world.run(0.6)
    controller = bob.position_controller
    assert controller.trajectory is not None and controller.trajectory.velocity[0] < -1.0
    here = controller.trajectory.position[0]
    controller.lower[0] = here - 0.02  # braking from > 1 rad/s at 5 rad/s^2 needs > 0.1 rad
    back = bob.positions.copy()
    back[0] = here + 0.1
    with pytest.raises(armfleet.ArmfleetError, match=r"bob_panda_joint1 to .* outside its limits"):
        bob.move_to(back)
    assert controller.is_moving  # the current motion goes on


def test_a_joint_a_hair_past_its_limit_can_move_back(world: armfleet.World) -> None:
    """After an impact a joint may rest a little beyond its limit (the soak found one at
    1.7628 + 1e-6): plans that start there and stay within the limits are accepted."""
    bob = world.spawn("bob")
    controller = bob.position_controller
    assert controller.trajectory is not None
    upper = controller.upper[1]
    controller.trajectory.position[1] = upper + 1e-4  # where an impact left joint 2
    inside = bob.positions
    inside[1] = upper - 0.2
    controller.plan(inside)  # no error: back inside
    further = controller.trajectory.position.copy()
    further[2] += 0.3
    further[1] = upper
    controller.plan(further)  # joint 2 goes back to its limit, joint 3 elsewhere: fine


#: The move of benchmarks/fleet.py's tracking comparison, from the Panda's home [rad].
BENCHMARK_MOVE_RAD = np.array([0.8, 0.6, -0.7, 0.8, 0.9, -0.8, 0.9])


def test_tracks_at_least_as_well_as_position_control_with_velocity_feed_forward() -> None:
    """The peer a user would pick: PyBullet's POSITION_CONTROL motors given Ruckig's positions
    and velocities each step, with the URDF effort limits. On the same move armfleet's
    torques (never clipped) track at least as well.

    Each is measured where it does best: armfleet's reference for t against the state at
    t; the motors' target for t against the state after the step, compared with the
    reference for t + dt (as benchmarks/fleet.py does).
    """
    with armfleet.World() as world:
        arm = world.spawn("bob")
        start = arm.positions
        errors: list[float] = []
        world.bus.subscribe(
            "/bob/position_controller/state",
            lambda s: errors.append(float(np.abs(s.reference_position - s.position).max())),
        )
        arm.move_to(start + BENCHMARK_MOVE_RAD)
        run_until_still(world, arm)
        controller = arm.position_controller
        assert controller.saturation_steps.sum() == 0, "physical torques, within the limits"
        ours = max(errors)
        reference = JerkLimitedTrajectory(
            start,
            world.dt,
            controller.max_velocity,
            np.full(start.size, float(controller.parameters["max_acceleration_rad_s2"])),
            np.full(start.size, float(controller.parameters["max_jerk_rad_s3"])),
        )
    with armfleet.World() as world:
        arm = world.spawn("bob")
        assert np.array_equal(arm.positions, start)
        arm.controller_manager.shutdown()  # brakes on; the arm joints' motors take over
        client, body = world.physics_client, arm.body.body_id
        chain = arm.kinematics.arm_indices
        joints = [arm.body.joint_indices[i] for i in chain]
        effort = arm.kinematics.effort_limit[chain].tolist()
        reference.follow(reference.plan(start + BENCHMARK_MOVE_RAD))
        theirs = 0.0
        while reference.moving:
            p.setJointMotorControlArray(
                body, joints, p.POSITION_CONTROL, targetPositions=reference.position.tolist(),
                targetVelocities=reference.velocity.tolist(), forces=effort,
                physicsClientId=client,
            )  # fmt: skip
            p.stepSimulation(physicsClientId=client)
            reference.advance()
            measured = np.array(
                [s[0] for s in p.getJointStates(body, joints, physicsClientId=client)]
            )
            theirs = max(theirs, float(np.abs(reference.position - measured).max()))
    print(
        f"max tracking error: armfleet {ours:.2e} rad, POSITION_CONTROL + velocity {theirs:.2e} rad"
    )
    assert theirs > 1e-6, "the peer was measured"
    assert ours <= theirs


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_a_move_on_ruckigs_case_boundary_is_planned_and_reached(compiled: bool) -> None:
    """A move from rest of exactly 2 a^3 / j^2 (0.1 rad with the shipped 5 rad/s^2 and
    50 rad/s^3) lies on the boundary between two of Ruckig's profile cases, where Ruckig
    0.19 raises instead of planning: every joint of a Panda moved by it gets there."""
    with armfleet.World(compiled_control=compiled) as world:
        bob = world.spawn("bob")
        parameters = bob.position_controller.parameters
        step = 2 * parameters["max_acceleration_rad_s2"] ** 3 / parameters["max_jerk_rad_s3"] ** 2
        assert step == pytest.approx(0.1)
        trajectory = bob.position_controller.trajectory
        assert trajectory is not None
        # Ruckig plans from the reference, which the arm follows within its tracking error.
        arm = bob.kinematics.arm_indices
        target = trajectory.position[arm] + step
        bob.move_to(target)
        world.run(3.0)
        assert not bob.is_moving
        assert np.abs(np.asarray(bob.positions) - target).max() < 1e-3
