"""PyBullet's forward dynamics of an armfleet arm equal Pinocchio's on the upstream model.

The reference is independent of armfleet's description code: a Pinocchio model
built straight from the upstream URDF that the model's xacro names (in
example-robot-data), with that file's joint damping. For a moving arm at random
states (positions within the limits, velocities up to 0.8 of the velocity limit or
1.6 rad/s, no contact) and random torques (up to 0.3 of the effort limits),
PyBullet's one-step acceleration ``(v1 - v0) / dt`` must equal
``pin.aba(q0, v0, tau - damping * v0)``.

PyBullet integrates with semi-implicit Euler: ``v1 = v0 + dt a(q0, v0, tau)`` then
``q1 = q0 + dt v1`` (checked here too; the position controller's law relies on it),
so the velocity change of one step is exactly ``dt`` times the acceleration at the
start of the step.

Tolerance: 1e-5 rad/s^2 (or m/s^2 for the fingers). Measured 2026-11-23 here:
xarm7 1.1e-6 (at accelerations up to 5e4), Panda 3.4e-7 (2e3; 3e-6 seen with torques
up to half the limits), z1 4e-8, URs 4e-12: rounding, largest where PyBullet
re-expresses inertias in principal axes. Bullet's default link damping (0.04, on until
armfleet turned it off) made 0.27 to 0.51 rad/s^2 here.
"""

from __future__ import annotations

import re
import sysconfig
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pinocchio as pin
import pybullet as p
import pytest

import armfleet
from armfleet.description import ModelLibrary

ACCELERATION_TOLERANCE = 1e-5  # [rad/s^2]
#: q1 - (q0 + dt v1): rounding only [rad].
INTEGRATOR_TOLERANCE_RAD = 1e-12
STATES = 10
EFFORT_FRACTION = 0.3
MAX_SPEED_RAD_S = 2.0
#: Where example-robot-data's ``package://example-robot-data/...`` files are.
SHARE = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
UPSTREAM_PROPERTY = re.compile(r'name="armfleet_upstream_urdf"\s+value="package://([^"]+)"')


def upstream_model(model: str) -> pin.Model:
    """Pinocchio's model of the upstream URDF that ``description/<model>.urdf.xacro`` wraps."""
    found = UPSTREAM_PROPERTY.search(ModelLibrary().path(model).read_text())
    assert found, f"{model}: no armfleet_upstream_urdf property"
    return pin.buildModelFromUrdf(str(SHARE / found.group(1)))


class LimpArm:
    """``model`` spawned as bob, its controllers stopped and PyBullet's motors off, so
    the torques given to :meth:`step` are the only ones applied."""

    def __init__(self, world: armfleet.World, model: str, reference: pin.Model) -> None:
        arm = world.spawn("bob", model=model)
        arm.controller_manager.shutdown()
        self.client, self.body, self.dt = world.physics_client, arm.body.body_id, world.dt
        by_name = {
            p.getJointInfo(self.body, i, physicsClientId=self.client)[1].decode(): i
            for i in range(p.getNumJoints(self.body, physicsClientId=self.client))
        }
        #: PyBullet joint index of each of the reference's joints, in its order.
        self.joints = [by_name[f"bob_{name}"] for name in list(reference.names)[1:]]
        p.setJointMotorControlArray(
            self.body, self.joints, p.VELOCITY_CONTROL,
            forces=[0.0] * len(self.joints), physicsClientId=self.client,
        )  # fmt: skip

    def place(self, q: np.ndarray, v: np.ndarray) -> bool:
        """Set the state; whether the arm is free of contacts there."""
        for joint, position, velocity in zip(self.joints, q, v, strict=True):
            p.resetJointState(self.body, joint, position, velocity, physicsClientId=self.client)
        p.performCollisionDetection(physicsClientId=self.client)
        return not p.getContactPoints(bodyA=self.body, physicsClientId=self.client)

    def step(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Apply ``tau`` for one physics step; the positions and velocities after it."""
        p.setJointMotorControlArray(
            self.body, self.joints, p.TORQUE_CONTROL, forces=tau.tolist(),
            physicsClientId=self.client,
        )  # fmt: skip
        p.stepSimulation(physicsClientId=self.client)
        states = p.getJointStates(self.body, self.joints, physicsClientId=self.client)
        return np.array([s[0] for s in states]), np.array([s[1] for s in states])


class Step(NamedTuple):
    """One physics step from a moving state: before (q, v), torques, after."""

    reference: pin.Model
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    q_next: np.ndarray
    v_next: np.ndarray
    dt: float


def random_steps(model: str) -> Iterator[Step]:
    """One step from each of STATES random contact-free moving states of ``model``."""
    reference = upstream_model(model)
    rng = np.random.default_rng(14)
    lower, upper = reference.lowerPositionLimit, reference.upperPositionLimit
    speed = np.minimum(reference.velocityLimit, MAX_SPEED_RAD_S) * 0.8
    with armfleet.World() as world:
        arm = LimpArm(world, model, reference)
        done = 0
        for _ in range(50 * STATES):
            q = lower + (upper - lower) * rng.uniform(0.2, 0.8, reference.nq)
            v = speed * rng.uniform(-1.0, 1.0, reference.nv)
            if not arm.place(q, v):  # a contact force would be in the step: another state
                continue
            tau = EFFORT_FRACTION * reference.effortLimit * rng.uniform(-1.0, 1.0, reference.nv)
            yield Step(reference, q, v, tau, *arm.step(tau), world.dt)
            done += 1
            if done == STATES:
                return
    pytest.fail(f"{model}: fewer than {STATES} contact-free states in {50 * STATES} samples")


@pytest.mark.parametrize("model", ModelLibrary().names)
def test_pybullet_accelerations_equal_pinocchio_aba_on_the_upstream_model(model: str) -> None:
    worst, largest = 0.0, 0.0
    for step in random_steps(model):
        reference, q, v = step.reference, step.q, step.v
        expected = pin.aba(
            reference, reference.createData(), q, v, step.tau - reference.damping * v
        )
        measured = (step.v_next - v) / step.dt
        worst = max(worst, float(np.abs(measured - expected).max()))
        largest = max(largest, float(np.abs(expected).max()))
    print(f"{model}: |a_pybullet - a_aba| <= {worst:.2e} rad/s^2 at |a| up to {largest:.0f}")
    assert worst < ACCELERATION_TOLERANCE


@pytest.mark.parametrize("model", ["panda", "ur5"])
def test_pybullet_integrates_with_semi_implicit_euler(model: str) -> None:
    for step in random_steps(model):
        assert np.abs(step.v_next - step.v).min() > 0.0  # every joint accelerated
        semi_implicit = step.q + step.dt * step.v_next
        assert np.abs(step.q_next - semi_implicit).max() < INTEGRATOR_TOLERANCE_RAD


def test_a_free_object_keeps_its_momentum_in_flight(world: armfleet.World) -> None:
    """A box thrown high above the floor: gravity is the only force. Its horizontal velocity
    and its spin about a principal axis stay as they were (Bullet's default damping took
    0.04/s off both); its vertical velocity is exactly -g t."""
    box = world.add_object("box", "box", size=(0.1, 0.2, 0.3), mass=1.0, at=(0.0, 3.0, 5.0))
    client = world.physics_client
    p.resetBaseVelocity(box.body_id, (1.0, 0.0, 0.0), (0.0, 0.0, 3.0), physicsClientId=client)
    steps = 200  # 0.2 s: falls 0.2 m
    world.run(steps * world.dt)
    gravity = p.getPhysicsEngineParameters(physicsClientId=client)["gravityAccelerationZ"]
    assert np.abs(box.velocity - (1.0, 0.0, gravity * steps * world.dt)).max() < 1e-9
    assert np.abs(box.angular_velocity - (0.0, 0.0, 3.0)).max() < 1e-9
