"""Typed messages carried on the bus, shaped like their ROS 2 counterparts."""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
#: Joint positions as given by users: a list, tuple or array of floats.
Positions = Sequence[float] | npt.NDArray[np.floating[Any]]


@dataclass(frozen=True)
class JointState:
    """``sensor_msgs/JointState``: one sample of an arm's joints.

    Attributes:
        stamp: simulated time of the sample [s].
        name: prefixed joint names.
        position: joint positions [rad or m].
        velocity: joint velocities [rad/s or m/s].
        effort: commanded joint efforts [Nm or N].
    """

    stamp: float
    name: tuple[str, ...]
    position: FloatArray
    velocity: FloatArray
    effort: FloatArray


@dataclass(frozen=True)
class JointCommand:
    """``std_msgs/Float64MultiArray`` on ``/<arm>/position_controller/commands``.

    Attributes:
        positions: target positions, one per controlled joint, in
            ``Arm.joint_names`` order [rad or m].
    """

    positions: tuple[float, ...]


@dataclass(frozen=True)
class ControllerState:
    """Reference and feedback of a position controller at one update.

    Attributes:
        stamp: simulated time [s].
        name: controlled joint names.
        reference_position, reference_velocity, reference_acceleration: the
            Ruckig reference at ``stamp``.
        position, velocity: the measured state at ``stamp``.
        moving: whether the reference is still in motion.
    """

    stamp: float
    name: tuple[str, ...]
    reference_position: FloatArray
    reference_velocity: FloatArray
    reference_acceleration: FloatArray
    position: FloatArray
    velocity: FloatArray
    moving: bool


@dataclass(frozen=True)
class TransformStamped:
    """``geometry_msgs/TransformStamped``: pose of ``child_frame_id`` in ``frame_id``.

    Attributes:
        stamp: simulated time [s].
        frame_id: parent frame.
        child_frame_id: child frame.
        matrix: 4x4 homogeneous transform parent -> child (translation in [m]).
    """

    stamp: float
    frame_id: str
    child_frame_id: str
    matrix: FloatArray


@dataclass(frozen=True)
class TFMessage:
    """``tf2_msgs/TFMessage``: a batch of transforms."""

    transforms: tuple[TransformStamped, ...]


class BringupStage(enum.Enum):
    """Stages an arm passes through, in this order, before the next arm starts."""

    SPAWNED = "spawned"
    BROADCASTER_ACTIVE = "joint_state_broadcaster active"
    CONTROLLER_ACTIVE = "position_controller active"
    READY = "ready"


@dataclass(frozen=True)
class BringupEvent:
    """Published on ``/bringup`` as an arm reaches a stage.

    Attributes:
        arm: arm name.
        stage: the stage reached.
        stamp: simulated time [s].
        wall_time: seconds since the arm's bring-up started (wall clock).
    """

    arm: str
    stage: BringupStage
    stamp: float
    wall_time: float


@dataclass(frozen=True)
class Contact:
    """One contact between two bodies, as PyBullet reports it after a step.

    Attributes:
        body_a, body_b: arm names, or ``"ground"``.
        link_a, link_b: link names (empty for the ground).
        position: contact point on ``body_a`` in the world [m].
        normal: contact normal from ``body_b`` to ``body_a``.
        depth: penetration depth [m], >= 0.
    """

    body_a: str
    link_a: str
    body_b: str
    link_b: str
    position: tuple[float, float, float]
    normal: tuple[float, float, float]
    depth: float

    @property
    def pair(self) -> tuple[str, str]:
        """The two links in contact, ordered (``"ground"`` for the floor)."""
        first, second = self.link_a or self.body_a, self.link_b or self.body_b
        return (first, second) if first <= second else (second, first)


@dataclass(frozen=True)
class CollisionReport:
    """Published on ``/collisions`` at every step with contacts, and once when they end.

    Attributes:
        stamp: simulated time [s].
        contacts: every counted contact of that step.
    """

    stamp: float
    contacts: tuple[Contact, ...]


class ArmMode(enum.Enum):
    """What an arm is doing, as reported on ``/<arm>/status``."""

    HOLDING = "holding"
    MOVING = "moving"
    PROTECTIVE_STOP = "protective stop"
    ERROR = "error"


@dataclass(frozen=True)
class ArmStatus:
    """Published on ``/<arm>/status`` at 10 Hz and at once when a stop or fault happens.

    Attributes:
        stamp: simulated time [s].
        arm: arm name.
        mode: what the arm is doing.
        reason: why it is stopped or in error ("" otherwise).
        saturation_steps: per movable joint, the control updates whose torque hit
            the URDF effort limit since spawn.
    """

    stamp: float
    arm: str
    mode: ArmMode
    reason: str
    saturation_steps: tuple[int, ...]


class GripperMode(enum.Enum):
    """What a gripper is doing, as reported on ``/<arm>/gripper_controller/state``."""

    MOVING = "moving"  # fingers on their way to a commanded width
    AT_WIDTH = "at width"  # fingers at the commanded width (open, or a given width)
    CLOSING = "closing"  # closing until the fingers are blocked
    SQUEEZING = "squeezing"  # blocked by something: pressing with the grasp force
    CLOSED = "closed"  # closed on nothing: the fingers met their limit


@dataclass(frozen=True)
class GripperCommand:
    """On ``/<arm>/gripper_controller/commands``: go to a width, or close with a force.

    Attributes:
        width: target opening between the finger pads [m]; ignored when ``grasp``.
        grasp: close until blocked, then press with ``force``.
        force: force limit of each finger [N] (the grasp force when squeezing).
    """

    width: float
    grasp: bool
    force: float


@dataclass(frozen=True)
class GripperState:
    """Published on ``/<arm>/gripper_controller/state`` (a ``control_msgs/GripperCommand``
    feedback in spirit).

    Attributes:
        stamp: simulated time [s].
        width: measured opening between the finger pads [m].
        target_width: where the fingers are going [m] (0 while closing).
        force: force each finger presses with [N] (commanded; positive closes).
        mode: what the gripper is doing.
        holding: squeezing something that both finger pads touch.
    """

    stamp: float
    width: float
    target_width: float
    force: float
    mode: GripperMode
    holding: bool


@dataclass(frozen=True)
class PlannedMotion:
    """Published on ``/<arm>/planned_motion`` when a collision-free plan starts on the arm
    (a ``moveit_msgs/DisplayTrajectory`` in spirit): the path it will follow.

    Attributes:
        stamp: simulated time the motion starts [s].
        name: the arm's controlled joint names (``Arm.joint_names``).
        time_from_start: time of each waypoint after ``stamp`` [s]; the last is the duration.
        positions: waypoints (rows) of the joint path, one column per joint [rad or m];
            between two waypoints the joints move in a straight line.
        tool_path: world positions (rows, x y z [m]) of the arm's tool0 along the motion,
            from start to goal, for drawing.
    """

    stamp: float
    name: tuple[str, ...]
    time_from_start: tuple[float, ...]
    positions: FloatArray
    tool_path: FloatArray

    @property
    def duration(self) -> float:
        """How long the motion lasts [s]."""
        return self.time_from_start[-1] if self.time_from_start else 0.0
