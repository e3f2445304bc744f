"""Play a recording back into the MeshCat viewer, or export it as a standalone HTML replay.

Nothing is simulated: the viewer is started without a world, each recorded arm
is rebuilt from its URDF (:class:`ReplayArm`), and the recorded joint
positions are pushed at their recorded times (live: paced to the wall clock;
export: as fast as possible, then :meth:`Viewer.save`).

The viewer takes arms and ticks as a world gives them (``add_arm(arm)``,
``tick(world)`` reading ``world.time``); :class:`ReplayClock` and
:class:`ReplayArm` provide just what it reads.

A live replay can hold its start until someone watches (``armfleet replay`` waits for a
browser): the recording's *opening*, its arms coming up and standing still, is shown at
once, then ``on_opened`` is called (it waits), and only then does the clock start. A
15.8 s recording played at 2x had ended before its page was open (issue 28).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, cast

import numpy as np

from armfleet import topics
from armfleet.checks.user_paths import given_path
from armfleet.description import ModelLibrary
from armfleet.errors import ArmfleetError
from armfleet.messages import JointCommand
from armfleet.recording.errors import RecordingError
from armfleet.recording.reader import Recording
from armfleet.recording.replay_arm import ReplayArm
from armfleet.recording.replay_stream import (
    ArmAppeared,
    ArmRemoved,
    JointPositions,
    MotionChanged,
    PlanStarted,
    TargetSent,
    replay_events,
)
from armfleet.runtime.bus import Bus

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.viewer import Viewer
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: Joint states per second and arm taken from the recording (the viewer shows 30).
REPLAY_RATE_HZ = 60.0
#: Longest sleep between two checks of the wall clock while paced [s].
MAX_SLEEP_S = 0.1
#: The longest an opening lasts, in replay time [s]: arms standing still after it are
#: replayed at their pace.
OPENING_MAX_S = 1.0
#: Joint motion an opening takes for standing still (an arm settling as it comes up)
#: [rad or m]; the viewer does not redraw below 1e-5.
STILL_TOLERANCE = 1e-4


class ReplayTarget(Protocol):
    """What a replay drives: the parts of :class:`armfleet.viewer.Viewer` it uses."""

    def expect_arms(self, positions: Mapping[str, Sequence[float]]) -> None: ...

    def add_arm(self, arm: Arm) -> None: ...

    def remove_arm(self, name: str) -> None: ...

    def tick(self, world: World) -> None: ...


class ReplayClock:
    """Stands in for the world in ``Viewer.tick``: the replay's time since the start [s]."""

    def __init__(self) -> None:
        self.time = 0.0


class ReplayPlayer:
    """Plays ``recording`` into a viewer (or any :class:`ReplayTarget`).

    Args:
        recording: an armfleet recording.
        target: the viewer.
        rate_hz: joint states per second and arm taken from the file; all if None.
        models: where to find models whose recorded meshes are not on this machine.
    """

    def __init__(
        self,
        recording: Recording,
        target: ReplayTarget,
        rate_hz: float | None = REPLAY_RATE_HZ,
        models: ModelLibrary | None = None,
    ) -> None:
        if not recording.arms:
            raise RecordingError(f"{recording.path} holds no armfleet arm to replay")
        states = [recording.topics.get(topics.joint_states(name)) for name in recording.arm_names]
        if not any(info is not None and info.message_count for info in states):
            raise RecordingError(
                f"{recording.path} has no /<arm>/joint_states messages to replay "
                "(recorded with a topic filter?)"
            )
        self._recording = recording
        self._target = target
        self._rate_hz = rate_hz
        self._models = models or ModelLibrary()
        self._bus = Bus()
        self.clock = ReplayClock()
        #: Arms on show, by name.
        self.arms: dict[str, ReplayArm] = {}
        self._waiting: dict[str, ReplayArm] = {}  # appeared, shown at their first joint state
        #: Arms that could not be rebuilt here, and why.
        self.skipped: dict[str, str] = {}
        # Arms still shown from the previous play; kept if the opening brings them again.
        self._left_over: set[str] = set()
        self._placed: set[str] = set()  # arms given a joint state in this play

    def play(
        self,
        speed: float | None = 1.0,
        on_event: Callable[[float], None] | None = None,
        on_opened: Callable[[], None] | None = None,
    ) -> float:
        """Play to the end; returns the replayed duration [s].

        Args:
            speed: times real time (1.0: as recorded); None for as fast as possible.
            on_event: called with the replay time [s] after each event is shown.
            on_opened: called once the opening is shown: the arms of the recording's
                first :data:`OPENING_MAX_S` that come up and stand still until then,
                shown at once, unpaced. The clock starts when it returns (e.g. once a
                browser shows the arms). None: no opening, every event paced.
        """
        if speed is not None and not speed > 0:
            raise RecordingError(f"replay speed {speed} is invalid; give a factor > 0")
        start_ns = self._recording.start_ns or 0
        wall_start = time.monotonic()
        world = cast("World", self.clock)
        opening = on_opened is not None
        self.clock.time = 0.0
        self._placed.clear()
        self._left_over = set(self.arms)
        if not opening:  # played again from the start: no arm is up yet
            self._drop_left_over()
        if opening:  # framed in the viewer before any of their meshes is sent
            self._target.expect_arms(self._opening_arms())
        for event in replay_events(self._recording, self._rate_hz):
            replay_time = max(0.0, (event.time_ns - start_ns) / 1e9)
            if opening and not self._opens(event, replay_time):
                opening = False
                self._opened(on_opened)
                wall_start = time.monotonic() - self.clock.time / (speed or 1.0)
            if speed is not None and not opening:
                _sleep_until(wall_start + replay_time / speed)
            self._apply(event, replay_time)
            self.clock.time = replay_time
            self._target.tick(world)
            if on_event is not None:
                on_event(replay_time)
        if opening:  # the whole recording was its opening
            self._opened(on_opened)
        return self.clock.time

    def _opening_arms(self) -> dict[str, tuple[float, float, float]]:
        """Where the arms that may come up in the opening stand (base x, y, z) [m]."""
        last_ns = (self._recording.start_ns or 0) + round(OPENING_MAX_S * 1e9)
        return {
            arm.name: (arm.pose.x, arm.pose.y, arm.pose.z)
            for arm in self._recording.arms
            if arm.spawned_ns <= last_ns and arm.name not in self.skipped
        }

    def _opened(self, on_opened: Callable[[], None] | None) -> None:
        """The opening is shown: await no other arm, then let ``on_opened`` wait."""
        self._drop_left_over()  # shown last time, they come later in the recording
        self._target.expect_arms({})  # those that did not come yet come later, paced
        if on_opened is not None:
            on_opened()

    def _opens(self, event: Any, replay_time: float) -> bool:
        """Whether ``event`` belongs to the opening: arms coming up and standing still."""
        if replay_time > OPENING_MAX_S:
            return False
        if isinstance(event, ArmAppeared):
            return True
        if isinstance(event, MotionChanged):
            return not event.moving
        if isinstance(event, JointPositions):
            arm = self.arms.get(event.arm)
            if arm is None or event.arm not in self._placed:  # its first state: it is shown
                return True
            before = arm.body.position.copy()
            arm.set_positions(event.names, event.positions)
            moved = np.abs(arm.body.position - before)
            still = not bool(np.any(moved > STILL_TOLERANCE))  # NaN: unknown, not a move
            arm.body.position[:] = before
            return still
        return False  # a target, a plan, a removal: the run has begun

    def _apply(self, event: Any, replay_time: float) -> None:
        if isinstance(event, JointPositions):
            arm = self.arms.get(event.arm) or self._waiting.pop(event.arm, None)
            if arm is None:
                return
            self._placed.add(event.arm)
            arm.set_positions(event.names, event.positions)
            if event.arm not in self.arms:
                self.arms[event.arm] = arm
                self._target.add_arm(cast("Arm", arm))
        elif isinstance(event, ArmAppeared):
            name = event.arm.name
            if name in self._left_over and self.arms[name].record == event.arm:
                self._left_over.discard(name)  # played again: the same arm, already shown
                return
            self._left_over.discard(name)
            self._remove(name)
            try:
                arm = ReplayArm(event.arm, self._bus, self._models)
            except ArmfleetError as exc:  # show the others
                logger.warning("replay: %s", exc)
                self.skipped[event.arm.name] = str(exc)
                return
            self._waiting[event.arm.name] = arm
        elif isinstance(event, ArmRemoved):
            self._remove(event.name)
        elif isinstance(event, TargetSent):
            if event.arm in self.arms:
                topic = topics.position_commands(event.arm)
                self._bus.publish(topic, JointCommand(event.positions))
        elif isinstance(event, PlanStarted):
            if event.arm in self.arms:  # drawn by the viewer until it ends, as live
                plan = dataclasses.replace(event.plan, stamp=replay_time)
                self._bus.publish(topics.planned_motion(event.arm), plan)
        elif isinstance(event, MotionChanged):
            arm = self.arms.get(event.arm)
            if arm is not None:
                arm.is_moving = event.moving

    def _drop_left_over(self) -> None:
        for name in self._left_over:
            self._remove(name)
        self._left_over.clear()

    def _remove(self, name: str) -> None:
        self._waiting.pop(name, None)
        if self.arms.pop(name, None) is not None:
            self._target.remove_arm(name)


def _sleep_until(deadline: float) -> None:
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return
        time.sleep(min(left, MAX_SLEEP_S))


def start_replay_viewer(port: int | None = None) -> Viewer:
    """A viewer for a replay (no world, no physics).

    Raises:
        RecordingError: the viewer cannot start.
    """
    from armfleet.viewer import start_viewer

    viewer, reason = start_viewer(port)
    if viewer is None:
        raise RecordingError(f"cannot replay: {reason}")
    return viewer


def export_html(recording: Recording, path: str | Path, models: ModelLibrary | None = None) -> Path:
    """Write the standalone HTML replay of ``recording`` to ``path`` (plays from ``file://``).

    Raises:
        RecordingError: the viewer cannot start, or the file cannot be written.
    """
    from armfleet.viewer import ViewerError

    target = given_path(path, "HTML replay")
    viewer = start_replay_viewer()
    try:
        ReplayPlayer(recording, viewer, models=models).play(speed=None)
        try:
            return viewer.save(target)
        except ViewerError as exc:
            raise RecordingError(str(exc)) from None
    finally:
        viewer.close()
