"""A recording as a stream of replay events: arms coming and going, joint positions, targets.

This is what a replay shows, read from the file without simulating anything:
``/<arm>/joint_states`` (positions), ``/<arm>/position_controller/commands``
(targets), ``/<arm>/status`` (moving or not), ``/<arm>/planned_motion`` (the
path of a planned motion as it starts) and the arms' spawn and removal records.
With ``rate_hz``, joint states are thinned to at most that rate per arm (the
skipped ones are not even decoded); an arm's last state is always delivered.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass

from armfleet import topics
from armfleet.messages import PlannedMotion
from armfleet.recording.arm_record import ArmRecord
from armfleet.recording.encode import numbers_or_nan, planned_motion
from armfleet.recording.reader import Recording

logger = logging.getLogger("armfleet")

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class ArmAppeared:
    """An arm enters the scene (spawned, or there when recording started)."""

    time_ns: int
    arm: ArmRecord


@dataclass(frozen=True)
class ArmRemoved:
    """An arm leaves the scene."""

    time_ns: int
    name: str


@dataclass(frozen=True)
class JointPositions:
    """One ``/<arm>/joint_states`` sample.

    Attributes:
        names: joint names, in the message's order.
        positions: joint positions [rad or m].
    """

    time_ns: int
    arm: str
    names: tuple[str, ...]
    positions: tuple[float, ...]


@dataclass(frozen=True)
class TargetSent:
    """A target sent to an arm's position controller [rad or m]."""

    time_ns: int
    arm: str
    positions: tuple[float, ...]


@dataclass(frozen=True)
class MotionChanged:
    """An arm starts or stops moving (from ``/<arm>/status``)."""

    time_ns: int
    arm: str
    moving: bool


@dataclass(frozen=True)
class PlanStarted:
    """A planned motion starts on an arm (its ``stamp`` is the recorded simulated time)."""

    time_ns: int
    arm: str
    plan: PlannedMotion


ReplayEvent = ArmAppeared | ArmRemoved | JointPositions | TargetSent | MotionChanged | PlanStarted


def replay_events(recording: Recording, rate_hz: float | None = None) -> Iterator[ReplayEvent]:
    """The recording's replay events in time order.

    Args:
        recording: an armfleet recording (its arms come from its ``armfleet.arms.arm`` records).
        rate_hz: at most this many joint states per second per arm; all if None.
    """
    arms = {arm.name for arm in recording.arms}
    lifecycle: list[ReplayEvent] = []
    for arm in recording.arms:
        lifecycle.append(ArmAppeared(arm.spawned_ns, arm))
        if arm.removed_ns is not None:
            lifecycle.append(ArmRemoved(arm.removed_ns, arm.name))
    lifecycle.sort(key=lambda event: (event.time_ns, isinstance(event, ArmAppeared)))
    per_topic: dict[str, tuple[str, str]] = {}
    for name in arms:
        per_topic[topics.joint_states(name)] = (name, "state")
        per_topic[topics.position_commands(name)] = (name, "command")
        per_topic[topics.status(name)] = (name, "status")
        per_topic[topics.planned_motion(name)] = (name, "plan")
    period_ns = None if rate_hz is None else round(NS_PER_S / rate_hz)
    next_due: dict[str, int] = {}
    held: dict[str, tuple[int, bytes]] = {}  # an arm's newest state not delivered yet
    pending = iter(lifecycle)
    upcoming = next(pending, None)
    wanted = [topic for topic in per_topic if topic in recording.topics]
    for topic, time_ns, data in recording.raw_messages(wanted):
        while upcoming is not None and upcoming.time_ns <= time_ns:
            if isinstance(upcoming, ArmRemoved):
                yield from _release(recording, held, upcoming.name)
            yield upcoming
            upcoming = next(pending, None)
        name, kind = per_topic[topic]
        if kind == "state":
            if period_ns is not None and time_ns < next_due.get(name, time_ns):
                held[name] = (time_ns, data)
                continue
            if period_ns is not None:
                next_due[name] = time_ns + period_ns
            held.pop(name, None)
            yield _positions(recording, name, time_ns, data)
        elif kind == "command":
            message = recording.decode(topic, data)
            yield TargetSent(time_ns, name, tuple(float(v) for v in message["data"]))
        elif kind == "plan":
            try:
                plan = planned_motion(recording.decode(topic, data))
            except (KeyError, TypeError, ValueError) as exc:  # a file written elsewhere
                logger.warning("replay: a planned motion of %s cannot be read: %s", name, exc)
                continue
            yield PlanStarted(time_ns, name, plan)
        else:
            message = recording.decode(topic, data)
            yield MotionChanged(time_ns, name, message.get("mode") == "moving")
    for name in list(held):
        yield from _release(recording, held, name)
    while upcoming is not None:
        yield upcoming
        upcoming = next(pending, None)


def _positions(recording: Recording, arm: str, time_ns: int, data: bytes) -> JointPositions:
    message = recording.decode(topics.joint_states(arm), data)
    names = tuple(message["name"])
    positions = numbers_or_nan(message.get("position"), len(names))
    return JointPositions(time_ns, arm, names, positions)


def _release(
    recording: Recording, held: dict[str, tuple[int, bytes]], arm: str
) -> Iterator[JointPositions]:
    if arm in held:
        time_ns, data = held.pop(arm)
        yield _positions(recording, arm, time_ns, data)
