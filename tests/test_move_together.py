"""Time-synchronised motion of several arms, and the reference of single-arm motions:
a plain move_to is still exactly Ruckig's plan; a straight line can be stopped or
replaced mid-way."""

from __future__ import annotations

import numpy as np
import pytest
import ruckig

import armfleet
from armfleet.description import ModelLibrary
from armfleet.messages import FloatArray

MODELS = ModelLibrary().names


def away_from_home(arm: armfleet.Arm, offset_rad: float) -> FloatArray:
    """Home moved by ``offset_rad`` on every joint (towards the roomier side of its limits)."""
    home = np.array(arm.description.home)
    lower, upper = arm.joint_limits
    direction = np.where(upper - home >= home - lower, 1.0, -1.0)
    return np.clip(home + direction * offset_rad, lower, upper)


@pytest.mark.parametrize("model", MODELS)
def test_two_arms_with_different_distances_finish_on_the_same_step(model: str) -> None:
    with armfleet.World() as world:
        bob = world.spawn("bob", model=model)
        toby = world.spawn("toby", model=model, at=(3.0, 0.0))
        far, near = away_from_home(bob, 0.6), away_from_home(toby, 0.15)
        alone = bob.position_controller.plan(far).duration
        toby_alone = toby.position_controller.plan(near).duration
        duration = world.move_together({"bob": far, "toby": near})
        assert duration == pytest.approx(alone, abs=1e-9) and toby_alone < 0.8 * duration
        finished: dict[str, int] = {}
        steps = 0
        peak_velocity = {"bob": 0.0, "toby": 0.0}
        peak_acceleration = {"bob": 0.0, "toby": 0.0}
        while len(finished) < 2:
            world.step()
            steps += 1
            for arm in (bob, toby):
                trajectory = arm.position_controller.trajectory
                assert trajectory is not None
                peak_velocity[arm.name] = max(
                    peak_velocity[arm.name],
                    float(
                        np.max(np.abs(trajectory.velocity) / arm.position_controller.max_velocity)
                    ),
                )
                peak_acceleration[arm.name] = max(
                    peak_acceleration[arm.name], float(np.max(np.abs(trajectory.acceleration)))
                )
                if not arm.is_moving:
                    finished.setdefault(arm.name, steps)
        assert abs(finished["bob"] - finished["toby"]) <= 1, finished
        assert finished["bob"] == pytest.approx(duration / world.dt, abs=2)
        for arm in (bob, toby):
            assert peak_velocity[arm.name] <= 1.0 + 1e-9
            limit = arm.position_controller.parameters["max_acceleration_rad_s2"]
            assert peak_acceleration[arm.name] <= limit + 1e-9
        world.run(0.2)
        assert np.abs(bob.positions - far).max() < 1e-3
        assert np.abs(toby.positions - near).max() < 1e-3


def test_a_panda_and_a_ur5_with_a_tool0_pose_finish_together_within_their_limits() -> None:
    with armfleet.World() as world:
        bob = world.spawn("bob", model="panda")
        toby = world.spawn("toby", model="ur5", at=(2.0, 0.0))
        goal = world.tf.lookup("world", "bob_tool0")
        goal[:3, 3] += (0.1, 0.2, -0.15)
        world.move_together({"bob": goal, "toby": away_from_home(toby, 0.5)})
        ends: dict[str, float] = {}
        while len(ends) < 2:
            world.step()
            for arm in (bob, toby):
                if not arm.is_moving:
                    ends.setdefault(arm.name, world.time)
                velocity = np.abs(arm.body.velocity[arm.kinematics.arm_indices])
                assert np.all(velocity <= arm.kinematics.velocity_limit[arm.kinematics.arm_indices])
        assert abs(ends["bob"] - ends["toby"]) <= world.dt + 1e-12
        world.run(0.1)
        reached = world.tf.lookup("world", "bob_tool0")
        assert np.linalg.norm(reached[:3, 3] - goal[:3, 3]) < 1e-3


def test_one_bad_target_moves_no_arm() -> None:
    with armfleet.World() as world:
        bob = world.spawn("bob", model="panda")
        toby = world.spawn("toby", model="panda", at=(1.5, 0.0))
        lower, _ = toby.joint_limits
        bad = np.array(toby.description.home)
        bad[0] = lower[0] - 0.5
        with pytest.raises(armfleet.ArmfleetError, match=r"toby: target .* outside its limits"):
            world.move_together({"bob": away_from_home(bob, 0.4), "toby": bad})
        far = np.eye(4)
        far[:3, 3] = (0.0, 0.0, 4.0)
        with pytest.raises(armfleet.UnreachablePose):
            world.move_together({"bob": away_from_home(bob, 0.4), "toby": far})
        with pytest.raises(armfleet.ArmfleetError, match="no arm named 'tobi'"):
            world.move_together({"bob": away_from_home(bob, 0.4), "tobi": bad})
        world.step()
        assert not bob.is_moving and not toby.is_moving


def test_a_plain_move_to_follows_ruckigs_own_plan_exactly() -> None:
    """The sampled-reference mode must not touch a plain move: its reference, step by
    step, is the time-optimal Ruckig trajectory, so the torques (pinned to the control
    law by test_control_law) are what they were."""
    with armfleet.World() as world:
        arm = world.spawn("bob", model="panda")
        controller = arm.position_controller
        start, target = arm.positions, away_from_home(arm, 0.5)
        dofs = start.size
        reference = ruckig.InputParameter(dofs)
        trajectory = controller.trajectory
        assert trajectory is not None
        reference.current_position = trajectory.position.tolist()
        reference.target_position = target.tolist()
        reference.max_velocity = controller.max_velocity.tolist()
        reference.max_acceleration = [controller.parameters["max_acceleration_rad_s2"]] * dofs
        reference.max_jerk = [controller.parameters["max_jerk_rad_s3"]] * dofs
        expected = ruckig.Trajectory(dofs)
        ruckig.Ruckig(dofs, controller.period).calculate(reference, expected)
        assert arm.move_to(target) == pytest.approx(expected.duration, abs=1e-12)
        for k in range(1, round(expected.duration / controller.period)):
            world.step()
            position, velocity, acceleration = expected.at_time(k * controller.period)
            assert np.abs(trajectory.position - position).max() < 1e-9
            assert np.abs(trajectory.velocity - velocity).max() < 1e-9
            assert np.abs(trajectory.acceleration - acceleration).max() < 1e-9


def line_goal(world: armfleet.World) -> FloatArray:
    goal = world.tf.lookup("world", "bob_tool0")
    goal[:3, 3] += (0.15, 0.1, -0.1)
    return goal


def test_a_protective_stop_brakes_a_straight_line_mid_way() -> None:
    with armfleet.World() as world:
        arm = world.spawn("bob", model="panda")
        duration = arm.move_to_pose(line_goal(world), linear=True)
        world.run(0.4 * duration)
        assert arm.position_controller.protective_stop("test: stop mid-line")
        world.run(0.3)
        assert arm.mode is armfleet.ArmMode.PROTECTIVE_STOP and not arm.is_moving
        held = arm.positions
        world.run(0.2)
        assert np.abs(arm.positions - held).max() < 1e-4
        with pytest.raises(armfleet.ArmfleetError, match="protective stop"):
            arm.move_to_pose(line_goal(world), linear=True)


def test_a_new_goal_mid_line_replans_from_the_moving_reference() -> None:
    with armfleet.World() as world:
        arm = world.spawn("bob", model="panda")
        controller = arm.position_controller
        trajectory = controller.trajectory
        assert trajectory is not None
        duration = arm.move_to_pose(line_goal(world), linear=True)
        world.run(0.5 * duration)
        before_v, before_a = trajectory.velocity.copy(), trajectory.acceleration.copy()
        assert np.abs(before_v).max() > 0.05  # still going
        target = away_from_home(arm, 0.3)
        arm.move_to(target)
        # No jump: Ruckig takes over from the sampled reference's position, velocity and
        # acceleration, so the next reference differs by at most one period of jerk.
        world.step()
        jerk = controller.parameters["max_jerk_rad_s3"] * controller.period
        assert np.abs(trajectory.acceleration - before_a).max() <= jerk + 1e-9
        dv_bound = (np.abs(before_a) + jerk) * controller.period
        assert np.all(np.abs(trajectory.velocity - before_v) <= dv_bound + 1e-9)
        while arm.is_moving:
            world.step()
        world.run(0.1)
        assert np.abs(arm.positions - target).max() < 1e-3
