"""Every arm's joint arrays laid end to end, and their exchange with PyBullet.

ros2_control keeps the state and command interfaces of all hardware in one
resource manager; a world keeps them in one block, a row per quantity and a
column per movable joint, arm after arm. Each arm's arrays (``ArmBody.position``,
its position controller's reference, gains, limits ...) are views of its own
columns, so an arm still sees only its joints, while a fleet-wide operation
(read the physics, compute every arm's feedback, clip every torque) is one
call over a row instead of one call per arm.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pybullet as p

from armfleet.messages import FloatArray
from armfleet.physics.arm_body import ArmBody


class Row(enum.IntEnum):
    """The quantities kept per joint (one row of the block each)."""

    # The hardware interface: state and command (kept adjacent, copied together).
    POSITION = 0
    VELOCITY = 1
    EFFORT_COMMAND = 2
    # The position controller's reference, gains and limits.
    REFERENCE_POSITION = 3
    REFERENCE_VELOCITY = 4
    REFERENCE_ACCELERATION = 5
    KP = 6
    KD = 7
    DAMPING = 8
    EFFORT_LIMIT = 9
    NEGATIVE_EFFORT_LIMIT = 10
    # Scratch rows of the control law.
    ACCELERATION = 11
    TORQUE = 12
    CLIPPED_TORQUE = 13
    SCRATCH = 14
    # The gripper controller's reference and force, in its fingers' columns.
    FINGER_REFERENCE_POSITION = 15
    FINGER_REFERENCE_VELOCITY = 16
    FINGER_REFERENCE_ACCELERATION = 17
    FINGER_FORCE = 18


@dataclass(frozen=True)
class JointViews:
    """One arm's columns of every row of a :class:`JointMemory` (views, not copies).

    Attributes:
        columns: the arm's columns in the block.
        rows: the arm's part of each :class:`Row` (index with ``Row.X``).
        saturation_steps: the arm's part of the per-joint count of clipped torques.
        finger_blocked: per joint, whether a closing finger is blocked by something.
        finger_grasping: per joint, whether its finger is closing with a force.
    """

    columns: slice
    rows: FloatArray
    saturation_steps: npt.NDArray[np.int64]
    finger_blocked: npt.NDArray[np.bool_]
    finger_grasping: npt.NDArray[np.bool_]

    def row(self, row: Row) -> FloatArray:
        view: FloatArray = self.rows[row]
        return view


class JointMemory:
    """The joint block of one world (see the module docstring).

    Args:
        client: PyBullet physics client id of the world.
    """

    def __init__(self, client: int) -> None:
        self._client = client
        self.block: FloatArray = np.zeros((len(Row), 0))
        self.rows: tuple[FloatArray, ...] = tuple(self.block)
        self.saturation_steps: npt.NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        self.saturated: npt.NDArray[np.bool_] = np.zeros(0, dtype=bool)
        self.finger_blocked: npt.NDArray[np.bool_] = np.zeros(0, dtype=bool)
        self.finger_grasping: npt.NDArray[np.bool_] = np.zeros(0, dtype=bool)
        #: The bodies whose joints the block holds, with their first and end column.
        self._bodies: list[tuple[ArmBody, int, int]] = []

    @property
    def size(self) -> int:
        """Number of joints (columns)."""
        return int(self.block.shape[1])

    def lay_out(self, sizes: Sequence[int]) -> list[JointViews]:
        """Make a new block with ``sizes[i]`` columns for arm ``i``; return each arm's views.

        The caller copies each arm's values into its new views (the old block is
        dropped): see :meth:`ArmBody.bind` and ``PositionController.bind``.
        """
        total = sum(sizes)
        self.block = np.zeros((len(Row), total))
        #: The rows of the block as views, in :class:`Row` order (indexing the block
        #: with a Row at every step would cost more than the arithmetic for a few arms).
        self.rows = tuple(self.block[row] for row in Row)
        self.saturation_steps = np.zeros(total, dtype=np.int64)
        self.saturated = np.zeros(total, dtype=bool)
        self.finger_blocked = np.zeros(total, dtype=bool)
        self.finger_grasping = np.zeros(total, dtype=bool)
        views = []
        start = 0
        for size in sizes:
            columns = slice(start, start + size)
            views.append(
                JointViews(
                    columns,
                    self.block[:, columns],
                    self.saturation_steps[columns],
                    self.finger_blocked[columns],
                    self.finger_grasping[columns],
                )
            )
            start += size
        return views

    def attach(self, bodies: Sequence[ArmBody], views: Sequence[JointViews]) -> None:
        """The bodies whose joints the block holds, in column order (after :meth:`lay_out`)."""
        self._bodies = [
            (body, view.columns.start, view.columns.stop)
            for body, view in zip(bodies, views, strict=True)
        ]

    def read(self) -> None:
        """Fill the position and velocity rows of every arm from the physics engine."""
        client = self._client
        states: list[tuple[float, ...]] = []
        for body, _, _ in self._bodies:
            states += p.getJointStates(body.body_id, body.joint_indices, physicsClientId=client)
        self.rows[Row.POSITION][:] = [state[0] for state in states]
        self.rows[Row.VELOCITY][:] = [state[1] for state in states]

    def write(self) -> None:
        """Send every arm's effort command to the physics engine (braked arms: nothing)."""
        client = self._client
        forces = self.rows[Row.EFFORT_COMMAND].tolist()
        for body, start, stop in self._bodies:
            if body.torque_mode:
                p.setJointMotorControlArray(
                    body.body_id, body.joint_indices, p.TORQUE_CONTROL,
                    forces=forces[start:stop], physicsClientId=client,
                )  # fmt: skip
