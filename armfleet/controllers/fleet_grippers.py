"""Every fleet-path gripper updated in one pass over the joint memory.

What :meth:`GripperController.update` does for one gripper, done for all of them:
the blocked test of closing fingers and the law of fingers not yet squeezing
(:func:`~armfleet.controllers.finger_law.finger_efforts`) run once over every
finger column; only grippers that are squeezing something, or whose fingers just
closed on it, compute their coupled-finger law on their own, and so do grippers with mimic joints
or revolute jaws complete theirs (their leaders' efforts written first, as alone). Each
gripper then publishes its state and advances its reference as it would alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from armfleet.controllers.finger_law import finger_efforts
from armfleet.controllers.gripper_controller import GripperController
from armfleet.physics.joint_memory import JointMemory, Row


class FleetGrippers:
    """The grippers of one fleet plan, with their fingers' columns gathered once.

    Args:
        memory: the world's joint memory.
        grippers: grippers whose state is in the memory (``fleet_ready``).
    """

    def __init__(self, memory: JointMemory, grippers: Sequence[GripperController]) -> None:
        self._memory = memory
        self.grippers = tuple(grippers)
        columns = [gripper.memory_columns for gripper in self.grippers]
        assert all(c is not None for c in columns)  # fleet_ready grippers only
        sizes = [len(c) for c in columns if c is not None]
        self._columns = np.concatenate([c for c in columns if c is not None]).astype(np.intp)
        #: Where each gripper's fingers start in the gathered arrays.
        self._starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.intp)
        self._segments = [
            slice(int(start), int(start) + size)
            for start, size in zip(self._starts, sizes, strict=True)
        ]
        self._owner = np.repeat(np.arange(len(sizes)), sizes)
        self._mass = np.concatenate([g.finger_mass for g in self.grippers])
        self._stiffness = np.concatenate([g.stiffness for g in self.grippers])
        self._gain = np.concatenate([g.gain for g in self.grippers])
        self._block_distance = np.concatenate([g.block_distance for g in self.grippers])
        self._completing = [g for g in self.grippers if g.completes_efforts]

    def write_efforts(self) -> None:
        """Every gripper's finger efforts into the memory (before its reference advances)."""
        memory, columns = self._memory, self._columns
        fingers = memory.block[:, columns]  # every row of every finger: one gather
        q, v = fingers[Row.POSITION], fingers[Row.VELOCITY]
        reference = (
            fingers[Row.FINGER_REFERENCE_POSITION],
            fingers[Row.FINGER_REFERENCE_VELOCITY],
            fingers[Row.FINGER_REFERENCE_ACCELERATION],
        )
        blocked = memory.finger_blocked[columns]
        squeezing = self._all(blocked)
        grasping = memory.finger_grasping[columns]
        if grasping.any():
            closing = grasping & ~squeezing[self._owner]
            blocked |= closing & (q - reference[0] > self._block_distance)
            memory.finger_blocked[columns] = blocked
            closed = self._all(blocked)
            for index in np.flatnonzero(closed & ~squeezing):
                self.grippers[index].hold_where_closed(q[self._segments[index]])
            squeezing = closed
        effort = finger_efforts(
            q, v, reference, self._mass, self._stiffness, self._gain,
            fingers[Row.DAMPING], fingers[Row.FINGER_FORCE], blocked,
        )  # fmt: skip
        if squeezing.any():
            for index in np.flatnonzero(squeezing):
                part = self._segments[index]
                effort[part] = self.grippers[index].squeeze_efforts(q[part], v[part])
        memory.rows[Row.EFFORT_COMMAND][columns] = effort
        for gripper in self._completing:  # mimics and jaws: after the leaders, as alone
            gripper.complete_efforts()

    def _all(self, flags: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
        """Per gripper: whether all its fingers' ``flags`` are set."""
        every: npt.NDArray[np.bool_] = np.logical_and.reduceat(flags, self._starts)
        return every
