"""The peer: N Pandas in plain PyBullet, as a user who doesn't pick armfleet writes it.

The upstream Panda URDF loaded with ``loadURDF``'s default flags (so no self-collision,
every link kept), and per arm, at every step, one Ruckig update and PyBullet's
``POSITION_CONTROL`` fed Ruckig's positions and velocities (the feed-forward that makes
it track: ~3e-5 rad, see docs/performance.md), with the URDF effort limits as forces.
Targets are drawn as the fleet benchmark draws armfleet's, with the same limits.

It stands on armfleet's floor slab, so that only the arms differ (PyBullet's
``plane.urdf`` would cost the peer about 7 µs per Panda more: armfleet/physics/ground.py).
"""

from __future__ import annotations

import sysconfig
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pybullet as p
import ruckig

from armfleet.physics.ground import create_ground

PANDA_URDF = (
    Path(sysconfig.get_paths()["purelib"])
    / "cmeel.prefix/share/example-robot-data/robots/panda_description/urdf/panda.urdf"
)
#: The Panda's home (its SRDF's "default" state), as armfleet's description has it.
HOME = np.array([0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398])
#: armfleet's position_controller defaults, given to the peer's Ruckig too.
VELOCITY_SCALING = 0.95
MAX_ACCELERATION_RAD_S2 = 5.0
MAX_JERK_RAD_S3 = 50.0


@dataclass
class PlainArm:
    """One upstream Panda and its Ruckig."""

    body: int
    joints: list[int]
    lower: np.ndarray
    upper: np.ndarray
    forces: list[float]
    otg: ruckig.Ruckig
    input: ruckig.InputParameter
    output: ruckig.OutputParameter
    moving: bool = field(default=False)


class PlainFleet:
    """N upstream Pandas on a grid in their own PyBullet world (1 ms step by default)."""

    def __init__(self, arms: int, columns: int, dt: float = 0.001) -> None:
        self.client = p.connect(p.DIRECT)
        p.setTimeStep(dt, physicsClientId=self.client)
        p.setGravity(0.0, 0.0, -9.81, physicsClientId=self.client)
        create_ground(self.client)
        self.arms = [self._load(i // columns, i % columns, dt) for i in range(arms)]
        #: Targets given so far (the peer really moves: the benchmark reports it).
        self.targets_given = 0
        for arm in self.arms:  # a first output, so a step can be taken before any target
            arm.otg.update(arm.input, arm.output)
        self.snapshot = p.saveState(physicsClientId=self.client)

    def _load(self, x: float, y: float, dt: float) -> PlainArm:
        client = self.client
        body = p.loadURDF(
            str(PANDA_URDF), [float(x), float(y), 0.0], useFixedBase=True, physicsClientId=client
        )
        joints = [
            j
            for j in range(p.getNumJoints(body, physicsClientId=client))
            if p.getJointInfo(body, j, physicsClientId=client)[2] == p.JOINT_REVOLUTE
        ]
        info = [p.getJointInfo(body, j, physicsClientId=client) for j in joints]
        for joint, value in zip(joints, HOME, strict=True):
            p.resetJointState(body, joint, float(value), physicsClientId=client)
        dofs = len(joints)
        inp = ruckig.InputParameter(dofs)
        inp.current_position = HOME.tolist()
        inp.current_velocity = [0.0] * dofs
        inp.current_acceleration = [0.0] * dofs
        inp.target_position = HOME.tolist()
        inp.max_velocity = [VELOCITY_SCALING * row[11] for row in info]
        inp.max_acceleration = [MAX_ACCELERATION_RAD_S2] * dofs
        inp.max_jerk = [MAX_JERK_RAD_S3] * dofs
        return PlainArm(
            body,
            joints,
            np.array([row[8] for row in info]),
            np.array([row[9] for row in info]),
            [row[10] for row in info],
            ruckig.Ruckig(dofs, dt),
            inp,
            ruckig.OutputParameter(dofs),
        )

    def random_targets(self, rng: np.random.Generator) -> None:
        """A new target for every arm at rest: within reach of home, as for armfleet."""
        for arm in self.arms:
            if not arm.moving:
                target = np.clip(
                    HOME + rng.uniform(-0.4, 0.4, HOME.size), arm.lower + 0.05, arm.upper - 0.05
                )
                arm.input.target_position = target.tolist()
                arm.moving = True
                self.targets_given += 1

    def step(self) -> None:
        """The user's loop body: Ruckig and the motors per arm, then the physics."""
        client = self.client
        for arm in self.arms:
            if arm.moving:
                result = arm.otg.update(arm.input, arm.output)
                arm.output.pass_to_input(arm.input)
                arm.moving = result == ruckig.Result.Working
            p.setJointMotorControlArray(
                arm.body, arm.joints, p.POSITION_CONTROL,
                targetPositions=arm.output.new_position,
                targetVelocities=arm.output.new_velocity,
                forces=arm.forces, physicsClientId=client,
            )  # fmt: skip
        p.stepSimulation(physicsClientId=client)

    def tracking_error(self) -> float:
        """Largest |Ruckig position - measured position| over every arm joint now [rad]."""
        worst = 0.0
        for arm in self.arms:
            states = p.getJointStates(arm.body, arm.joints, physicsClientId=self.client)
            measured = np.array([state[0] for state in states])
            worst = max(worst, float(np.abs(measured - arm.output.new_position).max()))
        return worst

    def go_limp(self) -> None:
        """Motors off (torque mode, no torque): the bare physics of these bodies."""
        for arm in self.arms:
            p.setJointMotorControlArray(
                arm.body, arm.joints, p.VELOCITY_CONTROL, forces=[0.0] * len(arm.joints),
                physicsClientId=self.client,
            )  # fmt: skip

    def restore(self) -> None:
        p.restoreState(self.snapshot, physicsClientId=self.client)

    def close(self) -> None:
        p.disconnect(self.client)
