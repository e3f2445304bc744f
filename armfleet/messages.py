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
