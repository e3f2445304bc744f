"""Pinocchio model of one arm, built from the very URDF text PyBullet loaded.

A continuous joint is read as a revolute one with the limits -inf and +inf (one
coordinate per joint, as PyBullet has it: :mod:`~armfleet.kinematics.continuous_joints`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from armfleet.errors import DescriptionError
from armfleet.kinematics.continuous_joints import as_revolute, continuous_joint_names
from armfleet.messages import FloatArray


@dataclass(frozen=True)
class LinkEdge:
    """One URDF joint seen as a transform between two links.

    Attributes:
        parent, child: link names.
        fixed: whether the joint is fixed (its transform is static).
    """

    parent: str
    child: str
    fixed: bool


class ArmKinematics:
    """Kinematics and dynamics of one arm.

    The model's root is the world: its fixed ``world -> <prefix>base_link``
    joint carries the spawn pose, so every frame placement is a world pose.

    Args:
        urdf: URDF text with the arm's prefixed names.
        tool_frame: the flange frame whose support chain defines the arm joints.
    """

    def __init__(self, urdf: str, tool_frame: str) -> None:
        continuous = continuous_joint_names(urdf)
        try:
            self.model = pin.buildModelFromXML(as_revolute(urdf) if continuous else urdf)
            # Effort and velocity limits as the file gives them (as_revolute adds a
            # <limit> where a continuous joint has none): same joints, same velocity order.
            as_written = pin.buildModelFromXML(urdf) if continuous else self.model
        except (RuntimeError, ValueError) as exc:
            raise DescriptionError(f"Pinocchio cannot build the model: {exc}") from exc
        self.data = self.model.createData()
        if self.model.nq != self.model.nv:
            names = [
                self.model.names[j]
                for j in range(1, self.model.njoints)
                if self.model.joints[j].nq != self.model.joints[j].nv
            ]
            raise DescriptionError(
                f"joints of more than one coordinate are not simulated: {', '.join(names)}"
            )
        if not self.model.existFrame(tool_frame):
            raise DescriptionError(f"the description has no landmark frame {tool_frame!r}")
        tool_joint = self.model.frames[body_frame_id(self.model, tool_frame)].parentJoint
        chain = {j for j in self.model.supports[tool_joint] if j != 0}
        #: Names of all movable joints, in model (configuration) order.
        self.joint_names: tuple[str, ...] = tuple(self.model.names[1:])
        #: Indices (into q) of the joints between base_link and tool0.
        self.arm_indices = np.array([self.model.joints[j].idx_q for j in sorted(chain)])
        #: Indices (into q) of the other movable joints (fingers, ...).
        self.auxiliary_indices = np.array(
            [self.model.joints[j].idx_q for j in range(1, self.model.njoints) if j not in chain],
            dtype=int,
        )
        #: Per movable joint (q order): whether it is continuous (no position limit).
        self.continuous = np.array([name in continuous for name in self.joint_names], dtype=bool)
        self.model.lowerPositionLimit = np.where(
            self.continuous, -np.inf, self.model.lowerPositionLimit
        )
        self.model.upperPositionLimit = np.where(
            self.continuous, np.inf, self.model.upperPositionLimit
        )
        self.model.velocityLimit = as_written.velocityLimit.copy()
        self.model.effortLimit = as_written.effortLimit.copy()
        #: Position limits (q order) [rad or m]; -inf and +inf for a continuous joint.
        self.lower = np.array(self.model.lowerPositionLimit, dtype=float)
        self.upper = np.array(self.model.upperPositionLimit, dtype=float)
        self.velocity_limit = np.array(self.model.velocityLimit, dtype=float)
        self.effort_limit = np.array(self.model.effortLimit, dtype=float)
        self.damping = np.array(self.model.damping, dtype=float)
        self._damping_torque = np.zeros(self.model.nv)
        # A link and a joint may share a name (SO-100's "gripper"): the name is the link's.
        self._frame_ids = {frame.name: i for i, frame in enumerate(self.model.frames)}
        self._frame_ids |= {
            frame.name: i
            for i, frame in enumerate(self.model.frames)
            if frame.type == pin.FrameType.BODY
        }
        self._fk_q: FloatArray | None = None

    def mid_range(self) -> FloatArray:
        """The middle of every movable joint's range (q order), 0 for a continuous joint
        (it has none); a new array [rad or m]."""
        middle: FloatArray = np.zeros(self.model.nq)
        bounded = ~self.continuous
        middle[bounded] = 0.5 * (self.lower[bounded] + self.upper[bounded])
        return middle

    @property
    def link_names(self) -> tuple[str, ...]:
        """Every link (body frame) of the model, ``world`` included."""
        return tuple(f.name for f in self.model.frames if f.type == pin.FrameType.BODY)

    @property
    def frame_names(self) -> tuple[str, ...]:
        """Links and joints, without Pinocchio's ``universe``."""
        return tuple(f.name for f in self.model.frames if f.name != "universe")

    def has_frame(self, name: str) -> bool:
        return name in self._frame_ids

    def link_edges(self) -> tuple[LinkEdge, ...]:
        """Every URDF joint as parent link -> child link."""
        frames = self.model.frames
        edges = []
        for frame in frames:
            if frame.type != pin.FrameType.BODY or frame.name == "world":
                continue
            joint_frame = frames[frame.parentFrame]
            if joint_frame.type not in (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT):
                continue
            parent = frames[joint_frame.parentFrame].name
            edges.append(
                LinkEdge(parent, frame.name, joint_frame.type == pin.FrameType.FIXED_JOINT)
            )
        return tuple(edges)

    def update(self, q: FloatArray) -> None:
        """Compute every frame placement for configuration ``q`` (cached per q)."""
        if self._fk_q is not None and np.array_equal(self._fk_q, q):
            return
        pin.framesForwardKinematics(self.model, self.data, q)
        self._fk_q = q.copy()

    def world_pose(self, frame: str) -> FloatArray:
        """4x4 world pose of ``frame`` at the configuration of the last :meth:`update`."""
        return np.array(self.data.oMf[self._frame_ids[frame]].homogeneous)

    def relative_pose(self, parent: str, child: str) -> FloatArray:
        """4x4 pose of ``child`` in ``parent`` at the configuration of the last :meth:`update`."""
        placements = self.data.oMf
        relative = placements[self._frame_ids[parent]].actInv(placements[self._frame_ids[child]])
        return np.array(relative.homogeneous)

    def rnea(self, q: FloatArray, v: FloatArray, a: FloatArray) -> FloatArray:
        """Joint torques for acceleration ``a`` of the rigid bodies (Pinocchio's RNEA), without
        the joint damping; a new array."""
        tau: FloatArray = pin.rnea(self.model, self.data, q, v, a)
        return tau

    def inverse_dynamics(self, q: FloatArray, v: FloatArray, a: FloatArray) -> FloatArray:
        """Joint torques for acceleration ``a``: RNEA plus the URDF viscous damping.

        PyBullet applies the URDF joint damping (``-damping * v``); RNEA does not,
        so it is added here for the two to agree.
        """
        tau = self.rnea(q, v, a)
        np.multiply(self.damping, v, out=self._damping_torque)
        tau += self._damping_torque
        return tau


def body_frame_id(model: pin.Model, name: str) -> int:
    """The frame ``name``, its link's if a joint has the same name."""
    if model.existFrame(name, pin.FrameType.BODY):
        return int(model.getFrameId(name, pin.FrameType.BODY))
    return int(model.getFrameId(name))
