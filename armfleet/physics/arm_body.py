"""An arm's body in the PyBullet world: its joints' state and effort interfaces.

This is the arm's hardware interface in ros2_control terms: ``read()`` fills
the state (positions, velocities), controllers fill ``effort_command``, and
``write()`` sends it to the physics engine in torque mode.

The body is the description's lean URDF (:mod:`armfleet.physics.lean_urdf`):
its landmark links (``world``, ``base_link``, ``tool0`` ...) are not PyBullet links,
and its first link with mass or a collision shape is the base, link index -1.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence

import numpy as np
import pinocchio as pin
import pybullet as p

from armfleet.errors import DescriptionError
from armfleet.messages import FloatArray
from armfleet.physics.body_removal import remove_body
from armfleet.physics.lean_urdf import lean_urdf
from armfleet.physics.link_damping import disable_link_damping

#: Load flags: inertias from the file (so PyBullet and Pinocchio dynamics
#: agree, with Bullet's link damping off: see link_damping.py) and no visual
#: shapes (PyBullet renders nothing here; the viewer takes visuals from Pinocchio).
LOAD_FLAGS = (
    p.URDF_USE_INERTIA_FROM_FILE
    | p.URDF_IGNORE_VISUAL_SHAPES
    | p.URDF_USE_SELF_COLLISION
    | p.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT
)
_BRAKE_FORCE = 1e4


class ArmBody:
    """The PyBullet multibody of one arm.

    Args:
        client: PyBullet physics client id of the world.
        urdf: URDF text (absolute mesh paths) rooted at the world; its ``world``
            joint carries the spawn pose. Its lean form is loaded.
        joint_names: movable joints, in the order of every array here.
    """

    def __init__(self, client: int, urdf: str, joint_names: Sequence[str]) -> None:
        self._client = client
        lean = lean_urdf(urdf)
        #: The base (link index -1): the description's first link with mass or a shape.
        self.base_link = lean.base_link
        fd, path = tempfile.mkstemp(suffix=".urdf", prefix="armfleet-")
        try:
            with os.fdopen(fd, "w") as file:
                file.write(lean.text)
            self.body_id = p.loadURDF(
                path,
                basePosition=lean.base_pose[:3, 3].tolist(),
                baseOrientation=_quaternion(lean.base_pose),
                useFixedBase=True,
                flags=LOAD_FLAGS,
                physicsClientId=client,
            )
        except p.error as exc:
            raise DescriptionError(f"PyBullet cannot load the URDF: {exc}") from exc
        finally:
            os.unlink(path)
        disable_link_damping(self.body_id, client)
        self._link_index: dict[str, int] = {lean.base_link: -1}
        #: Per link index but the base's: (parent link index, whether its joint moves).
        self.link_parents: dict[int, tuple[int, bool]] = {}
        joint_index: dict[str, int] = {}
        for index in range(p.getNumJoints(self.body_id, physicsClientId=client)):
            info = p.getJointInfo(self.body_id, index, physicsClientId=client)
            joint_index[info[1].decode()] = index
            self._link_index[info[12].decode()] = index
            self.link_parents[index] = (info[16], info[2] != p.JOINT_FIXED)
        missing = [name for name in joint_names if name not in joint_index]
        if missing:
            self.remove()
            raise DescriptionError(f"PyBullet body lacks joints {', '.join(missing)}")
        self.joint_indices = [joint_index[name] for name in joint_names]
        n = len(self.joint_indices)
        self.position = np.zeros(n)
        self.velocity = np.zeros(n)
        self.effort_command = np.zeros(n)
        self._torque_mode = False
        self.engage_brakes()

    def bind(self, position: FloatArray, velocity: FloatArray, effort_command: FloatArray) -> None:
        """Keep :attr:`position`, :attr:`velocity` and :attr:`effort_command` in the given
        arrays from now on (views of the world's joint memory), with their current values."""
        position[:], velocity[:], effort_command[:] = (
            self.position,
            self.velocity,
            self.effort_command,
        )
        self.position, self.velocity, self.effort_command = position, velocity, effort_command

    @property
    def torque_mode(self) -> bool:
        """Whether the efforts are ours (brakes released)."""
        return self._torque_mode

    @property
    def link_names(self) -> tuple[str, ...]:
        """The links PyBullet simulates, the base first (no landmark links)."""
        return tuple(self._link_index)

    def link_index(self, link: str) -> int:
        return self._link_index[link]

    def reset(self, positions: FloatArray) -> None:
        """Teleport the joints to ``positions`` at rest (only before control starts)."""
        for index, value in zip(self.joint_indices, positions, strict=True):
            p.resetJointState(self.body_id, index, float(value), 0.0, physicsClientId=self._client)
        self.read()

    def read(self) -> None:
        """Fill :attr:`position` and :attr:`velocity` from the physics engine."""
        states = p.getJointStates(self.body_id, self.joint_indices, physicsClientId=self._client)
        self.position[:] = [state[0] for state in states]
        self.velocity[:] = [state[1] for state in states]

    def write(self) -> None:
        """Apply :attr:`effort_command` as joint torques (no-op while braked)."""
        if self._torque_mode:
            p.setJointMotorControlArray(
                self.body_id,
                self.joint_indices,
                p.TORQUE_CONTROL,
                forces=self.effort_command.tolist(),
                physicsClientId=self._client,
            )

    def engage_brakes(self) -> None:
        """Hold the joints with PyBullet's velocity motors, as a powered-off arm's brakes."""
        self._torque_mode = False
        self.effort_command[:] = 0.0
        p.setJointMotorControlArray(
            self.body_id,
            self.joint_indices,
            p.VELOCITY_CONTROL,
            targetVelocities=[0.0] * len(self.joint_indices),
            forces=[_BRAKE_FORCE] * len(self.joint_indices),
            physicsClientId=self._client,
        )

    def release_brakes(self) -> None:
        """Switch to torque mode: the built-in motors are disabled, efforts are ours."""
        p.setJointMotorControlArray(
            self.body_id,
            self.joint_indices,
            p.VELOCITY_CONTROL,
            forces=[0.0] * len(self.joint_indices),
            physicsClientId=self._client,
        )
        self._torque_mode = True

    def link_world_pose(self, link: str) -> FloatArray:
        """4x4 world pose of ``link``'s URDF frame, as PyBullet sees it."""
        index = self._link_index[link]
        if index == -1:  # PyBullet gives the base's inertial frame: undo its offset
            position, orientation = p.getBasePositionAndOrientation(
                self.body_id, physicsClientId=self._client
            )
            info = p.getDynamicsInfo(self.body_id, -1, physicsClientId=self._client)
            inertial = _matrix(info[3], info[4])
            return _matrix(position, orientation) @ np.linalg.inv(inertial)
        state = p.getLinkState(
            self.body_id, index, computeForwardKinematics=True, physicsClientId=self._client
        )
        return _matrix(state[4], state[5])

    def set_friction(self, link_index: int, lateral: float, spinning: float) -> None:
        """Friction coefficients of link ``link_index`` (Bullet multiplies those of a pair)."""
        p.changeDynamics(
            self.body_id,
            link_index,
            lateralFriction=lateral,
            spinningFriction=spinning,
            physicsClientId=self._client,
        )

    def bodies_touching(self, link_index: int) -> set[int]:
        """PyBullet ids of the other bodies in contact with link ``link_index`` now."""
        points = p.getContactPoints(
            bodyA=self.body_id, linkIndexA=link_index, physicsClientId=self._client
        )
        return {point[2] for point in points if point[2] != self.body_id and point[8] <= 0.0}

    def remove(self) -> None:
        """Take the body out of the world, and its collision filters with it."""
        remove_body(self._client, self.body_id)


def _matrix(position: Sequence[float], quaternion: Sequence[float]) -> FloatArray:
    """4x4 pose from a position and a PyBullet quaternion (x, y, z, w)."""
    matrix = np.eye(4)
    matrix[:3, :3] = np.reshape(p.getMatrixFromQuaternion(quaternion), (3, 3))
    matrix[:3, 3] = position
    return matrix


def _quaternion(pose: FloatArray) -> list[float]:
    """PyBullet quaternion (x, y, z, w) of a 4x4 pose's rotation."""
    x, y, z, w = pin.Quaternion(pose[:3, :3]).coeffs()
    return [float(x), float(y), float(z), float(w)]
