"""The optimised controller computes exactly the documented control law.

    tau = clip(RNEA(q, v, qdd_ref + kp (q_ref - q) + kd (v_ref - (h/2) qdd_ref - v))
               + damping * v, +-effort)

(h the physics step: the velocity semi-implicit Euler gives a state on the reference)
written here the plain way, for the arm joints (Ruckig reference) and the other
joints (held where they were at activation, zero velocity and acceleration),
except the gripper's fingers: the position controller leaves them to the
gripper_controller (zero acceleration, no feedback).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from armfleet.controllers.gripper_controller import finger_indices


@pytest.mark.parametrize("model", ["panda", "ur5"])
def test_torques_match_a_plain_implementation(model: str) -> None:
    rng = np.random.default_rng(5)
    with armfleet.World() as world:
        arm = world.spawn("bob", model=model)
        controller = arm.position_controller
        trajectory = controller.trajectory
        assert trajectory is not None
        kinematics = arm.kinematics
        chain, others = kinematics.arm_indices, kinematics.auxiliary_indices
        fingers = finger_indices(kinematics)
        assert (fingers.size > 0) == (model == "panda")
        kp, kd = controller.parameters["kp_s2"], controller.parameters["kd_s"]
        for _ in range(20):
            lower, upper = kinematics.lower, kinematics.upper
            q = lower + (upper - lower) * rng.uniform(0.1, 0.9, lower.size)
            v = rng.normal(size=q.size)
            arm.body.position[:], arm.body.velocity[:] = q, v
            trajectory.position[:] = q[chain] + rng.normal(scale=1e-3, size=chain.size)
            trajectory.velocity[:] = v[chain] + rng.normal(scale=1e-2, size=chain.size)
            trajectory.acceleration[:] = rng.normal(size=chain.size)
            q_ref, v_ref, a_ref = np.zeros(q.size), np.zeros(q.size), np.zeros(q.size)
            q_ref[others] = controller.held_positions
            q_ref[chain] = trajectory.position
            v_ref[chain] = trajectory.velocity
            a_ref[chain] = trajectory.acceleration
            acceleration = a_ref + kp * (q_ref - q) + kd * (v_ref - world.dt / 2 * a_ref - v)
            acceleration[fingers] = 0.0
            expected = (
                pin.rnea(kinematics.model, kinematics.model.createData(), q, v, acceleration)
                + np.asarray(kinematics.model.damping) * v
            )
            expected = np.clip(expected, -kinematics.effort_limit, kinematics.effort_limit)
            controller.update(world.time)
            assert np.abs(arm.body.effort_command - expected).max() < 1e-9
