"""An arm's position-controller reference and measured joints, read from a recording.

The data come from ``/<arm>/position_controller/state``
(``control_msgs/msg/JointTrajectoryControllerState``: ``reference.positions``
vs ``feedback.positions`` at every control update) and the command times from
``/<arm>/position_controller/commands``. Long recordings are thinned to at
most :data:`MAX_POINTS` samples for drawing; the largest error is found over
every sample.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from armfleet import topics
from armfleet.recording.encode import numbers_or_nan
from armfleet.recording.errors import RecordingError, UnknownRecordedArm
from armfleet.recording.reader import Recording

#: Samples kept per joint for drawing.
MAX_POINTS = 20_000

FloatArray = npt.NDArray[np.float64]


def state_topic(arm: str) -> str:
    return topics.position_controller_state(arm)


def command_topic(arm: str) -> str:
    return topics.position_commands(arm)


@dataclass(frozen=True)
class TrackingData:
    """Reference vs measured joint positions of one arm.

    Attributes:
        arm: arm name.
        model: its model ("" if the recording does not say).
        joint_names: controlled joints.
        prismatic: per joint, whether it is prismatic (positions in m, not rad).
        time_s: sample times (thinned) [s].
        reference: reference positions, samples x joints [rad or m].
        position: measured positions, samples x joints [rad or m].
        command_times_s: times at which targets were sent [s].
        samples: messages read (before thinning).
        worst_error: largest |reference - measured| over every sample [rad or m].
        worst_joint: index of the joint where it happened.
        worst_time_s: when it happened [s].
        rms_error: root mean square of reference - measured over every sample and joint.
    """

    arm: str
    model: str
    joint_names: tuple[str, ...]
    prismatic: tuple[bool, ...]
    time_s: FloatArray
    reference: FloatArray
    position: FloatArray
    command_times_s: tuple[float, ...]
    samples: int
    worst_error: float
    worst_joint: int
    worst_time_s: float
    rms_error: float

    @property
    def error(self) -> FloatArray:
        """reference - measured, samples x joints [rad or m]."""
        error: FloatArray = self.reference - self.position
        return error


def plottable_arms(recording: Recording) -> tuple[str, ...]:
    """Arms whose controller state was recorded, in spawn order (then by topic)."""
    names = [name for name in recording.arm_names if _count(recording, name)]
    for topic in recording.topics:
        parts = topic.split("/")
        if topic == state_topic(parts[1]) and parts[1] not in names and _count(recording, parts[1]):
            names.append(parts[1])
    return tuple(names)


def _count(recording: Recording, arm: str) -> int:
    info = recording.topics.get(state_topic(arm))
    return 0 if info is None else info.message_count


def tracking_data(recording: Recording, arm: str) -> TrackingData:
    """Read arm ``arm``'s tracking from ``recording``.

    Raises:
        UnknownRecordedArm: no such arm (the error lists the arms that can be plotted).
        RecordingError: the arm is there but its controller state was not recorded.
    """
    count = _count(recording, arm)
    if not count:
        known = arm in recording.arm_names or state_topic(arm) in recording.topics
        if not known:
            raise UnknownRecordedArm(recording.path, arm, plottable_arms(recording))
        raise RecordingError(
            f"{recording.path} has no {state_topic(arm)} messages to plot "
            "(recorded with a topic filter?)"
        )
    stride = max(1, math.ceil(count / MAX_POINTS))
    times: list[float] = []
    reference: list[list[float]] = []
    position: list[list[float]] = []
    names: tuple[str, ...] = ()
    worst = (-1.0, 0, 0.0)
    square_sum, values = 0.0, 0
    for i, message in enumerate(recording.messages([state_topic(arm)])):
        data = message.data
        joints = len(data["joint_names"])
        ref = np.array(numbers_or_nan(data["reference"].get("positions"), joints))
        pos = np.array(numbers_or_nan(data["feedback"].get("positions"), joints))
        error = np.abs(ref - pos)
        square_sum += float(np.sum(np.square(error)))
        values += error.size
        if error.size and np.nanmax(error) > worst[0]:
            joint = int(np.nanargmax(error))
            worst = (float(error[joint]), joint, message.time_s)
        if i % stride == 0:
            names = names or tuple(data["joint_names"])
            times.append(message.time_s)
            reference.append(ref.tolist())
            position.append(pos.tolist())
    commands = tuple(m.time_s for m in recording.messages([command_topic(arm)]))
    model = ""
    prismatic = tuple(False for _ in names)
    if arm in recording.arm_names:
        record = recording.arm(arm)
        model = record.model
        prismatic = _prismatic(record.urdf, names)
    return TrackingData(
        arm=arm,
        model=model,
        joint_names=names,
        prismatic=prismatic,
        time_s=np.array(times),
        reference=np.array(reference, dtype=float),
        position=np.array(position, dtype=float),
        command_times_s=commands,
        samples=count,
        worst_error=max(worst[0], 0.0),
        worst_joint=worst[1],
        worst_time_s=worst[2],
        rms_error=math.sqrt(square_sum / values) if values else 0.0,
    )


def _prismatic(urdf: str, joints: tuple[str, ...]) -> tuple[bool, ...]:
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError:
        return tuple(False for _ in joints)
    kinds = {j.get("name"): j.get("type") for j in root.iter("joint")}
    return tuple(kinds.get(name) == "prismatic" for name in joints)
