"""Record every topic of a world to an MCAP file, as ``ros2 bag record -a`` would.

>>> with armfleet.record(world, "run.mcap"):          # doctest: +SKIP
...     bob.move_to(target)
...     world.run(2.0)

What goes in the file:
    * every message of every topic (``subscribe_all``: this also turns on
      the topics published only when someone listens, ``/tf`` and
      ``/<arm>/position_controller/state``), JSON-encoded with ROS-shaped
      schemas (:mod:`armfleet.recording.schemas`), log time = simulated time [ns];
    * ``/tf_static`` as latched at the start, then as arms come;
    * per arm: its URDF (attachment ``<arm>.urdf``), an ``armfleet.arms.arm`` metadata
      record (model, pose, joints, spawn time), and ``/<arm>/robot_description``
      (``std_msgs/msg/String``, mesh paths as ``file://`` URIs, for this machine), and
      ``/<arm>/robot_meshes`` (``foxglove.SceneUpdate``: the link visuals with their mesh
      files inside, which any Foxglove draws: :mod:`armfleet.recording.robot_meshes`);
    * the launch spec, if given (attachment ``launch_spec.yaml``), and an
      ``armfleet.run`` metadata record (version, dt, start).

The recorder never stops the simulation: a message it cannot encode is
skipped with a warning.
"""

from __future__ import annotations

import datetime
import fnmatch
import functools
import logging
import os
import re
import weakref
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from armfleet import topics
from armfleet._version import __version__
from armfleet.checks.user_paths import given_path
from armfleet.errors import WorldClosed
from armfleet.messages import ArmStatus, BringupEvent, BringupStage
from armfleet.recording.arm_record import (
    ARM_METADATA,
    REMOVED_METADATA,
    RUN_METADATA,
    SPEC_MEDIA_TYPE,
    URDF_MEDIA_TYPE,
    arm_metadata,
    urdf_attachment,
)
from armfleet.recording.encode import MessageEncoder, StringEncoder, encoder_for, stamp_ns
from armfleet.recording.errors import RecordingError
from armfleet.recording.mcap_sink import CHUNK_BYTES, McapSink
from armfleet.recording.robot_meshes import ROBOT_MESHES, robot_meshes_message, robot_meshes_topic
from armfleet.recording.spec_snapshot import spec_text

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.runtime.bus import Subscription, Tap
    from armfleet.spec import FleetSpec
    from armfleet.world import World

logger = logging.getLogger("armfleet")

SUFFIX = ".mcap"
SPEC_ATTACHMENT = "launch_spec.yaml"
_MESH_PATH = re.compile(r'filename="(/[^"]*)"')


@dataclass
class _Channel:
    id: int
    encode: MessageEncoder
    #: Messages that tell about arms coming and going.
    watch: bool


class Recorder:
    """Writes the topics of ``world`` to an MCAP file between :meth:`start` and :meth:`stop`.

    Use it as a context manager, or through :func:`record`. The file is valid
    after :meth:`stop`, and readable up to its last complete chunk if the
    process dies before (see :func:`armfleet.recording.open_recording`).

    Args:
        world: the world to record.
        path: the ``.mcap`` file to write (replaced if it exists).
        spec: the launch spec of the run, stored in the file.
        topics: the topics to record, as names or glob patterns (``fnmatch``), e.g.
            ``["/bob/*", "/tf_static"]``; every topic if None. With names only, the
            recorder subscribes to just those: topics computed only for listeners
            (``/tf``, ``/<arm>/position_controller/state``) then cost nothing unless named.
        chunk_bytes: uncompressed size of the file's chunks [bytes].

    Raises:
        RecordingError: ``path`` does not end in ``.mcap``.
    """

    def __init__(
        self,
        world: World,
        path: str | Path,
        *,
        spec: FleetSpec | None = None,
        topics: Iterable[str] | None = None,
        chunk_bytes: int = CHUNK_BYTES,
    ) -> None:
        if not isinstance(path, str | os.PathLike):
            raise RecordingError(f"recording {path!r}: name an MCAP file ending in {SUFFIX}")
        self._path = given_path(path, "recording")
        if self._path.suffix.lower() != SUFFIX:
            raise RecordingError(f"recording {self._path}: name an MCAP file ending in {SUFFIX}")
        self._world = world
        self._spec = spec
        from armfleet.spec import FleetSpec  # imported for typing only at module level

        if spec is not None and not isinstance(spec, FleetSpec):
            raise RecordingError(
                f"recording {self._path}: spec must be an armfleet.FleetSpec (e.g. from "
                f"armfleet.load_spec), got {type(spec).__name__}"
            )
        if isinstance(topics, str | bytes):
            raise RecordingError(
                f"recording {self._path}: topics={topics!r} must be a list of topics or "
                f"patterns, e.g. [{topics!r}]"
            )
        self._patterns = None if topics is None else tuple(topics)
        if self._patterns is not None and not all(isinstance(t, str) for t in self._patterns):
            raise RecordingError(
                f"recording {self._path}: topics must be topic names or patterns (text), "
                f"e.g. ['/bob/*'], got {self._patterns!r}"[:400]
            )
        self._chunk_bytes = chunk_bytes
        self._sink: McapSink | None = None
        self._listening: list[Tap | Subscription] = []
        self._finalizer: weakref.finalize[Any, Any] | None = None
        self._channels: dict[str, _Channel | None] = {}
        self._arms: dict[str, Arm] = {}
        self._skipped: dict[str, int] = {}
        #: The arms' meshes, written when the file is completed (see :meth:`_add_meshes`).
        self._meshes: list[_PendingMeshes] = []

    # -- properties -------------------------------------------------------------------
    @property
    def path(self) -> Path:
        return self._path

    @property
    def active(self) -> bool:
        """Whether messages are being recorded."""
        return self._sink is not None and not self._sink.closed

    @property
    def message_count(self) -> int:
        """Messages written so far (robot descriptions included)."""
        return 0 if self._sink is None else self._sink.message_count

    @property
    def skipped(self) -> dict[str, int]:
        """Per topic, messages that could not be encoded (normally empty)."""
        return dict(self._skipped)

    # -- lifetime ---------------------------------------------------------------------
    def start(self) -> Recorder:
        """Open the file and record from now on; returns ``self``.

        Raises:
            RecordingError: already started, or the file cannot be created.
            WorldClosed: the world is closed.
        """
        if self._sink is not None:
            raise RecordingError(f"the recording {self._path} was already started")
        world = self._world
        if world.closed:
            raise WorldClosed()
        sink = McapSink(self._path, f"armfleet {__version__}", self._chunk_bytes)
        self._sink = sink
        # A script that never stops its recorder still leaves a complete file.
        self._finalizer = weakref.finalize(self, _complete, sink, self._meshes)
        now = self._now_ns()
        sink.add_metadata(
            RUN_METADATA,
            {
                "armfleet_version": __version__,
                "dt_s": repr(world.dt),
                "started_ns": str(now),
                "started_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(),
                "spec_source": "" if self._spec is None else self._spec.source,
                "log_time": "simulated time [ns]",
            },
        )
        if self._spec is not None:
            sink.attach(SPEC_ATTACHMENT, SPEC_MEDIA_TYPE, spec_text(self._spec).encode(), now)
        for arm in world.arms.values():
            self._add_arm(arm)
        self._open_advertised()
        self._listen()
        return self

    def _listen(self) -> None:
        bus = self._world.bus
        exact = self._patterns is not None and not any(map(_is_pattern, self._patterns))
        if not exact:
            for topic in bus.topics:
                for message in bus.latched(topic):
                    self._on_message(topic, message)
            self._listening.append(bus.subscribe_all(self._on_message))
            return
        # Named topics only: subscribe to just those, so that the topics computed only
        # for listeners (/tf, controller states) cost nothing unless named. Latched
        # messages come with the subscription.
        assert self._patterns is not None
        for topic in dict.fromkeys(self._patterns):
            self._listening.append(bus.subscribe(topic, functools.partial(self._on_message, topic)))
        if topics.BRINGUP not in self._patterns:  # still notice the arms that come
            self._listening.append(bus.subscribe(topics.BRINGUP, self._watch))

    def stop(self) -> None:
        """Stop recording and complete the file (summary, index); idempotent."""
        sink = self._sink
        if sink is None or sink.closed:
            return
        for listening in self._listening:
            listening.cancel()
        self._listening.clear()
        try:
            self._check_arms()
            self._open_advertised()
        finally:
            _complete(sink, self._meshes)
            if self._finalizer is not None:
                self._finalizer.detach()
        for topic, count in self._skipped.items():
            logger.warning("recording %s: %d message(s) of %s skipped", self._path, count, topic)

    def __enter__(self) -> Recorder:
        if self._sink is None:
            self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def __repr__(self) -> str:
        state = "recording" if self.active else ("stopped" if self._sink else "not started")
        return f"Recorder({str(self._path)!r}, {state}, {self.message_count} messages)"

    # -- messages ---------------------------------------------------------------------
    def _open_advertised(self) -> None:
        """Give every advertised topic its channel, messages or not (as ``ros2 bag``)."""
        for topic, message_type in self._world.bus.topics.items():
            if topic not in self._channels:
                self._open(topic, message_type)

    def _now_ns(self) -> int:
        return stamp_ns(self._world.time)

    def _on_message(self, topic: str, message: Any) -> None:
        channel = self._channels.get(topic, _UNSEEN)
        if channel is _UNSEEN:
            channel = self._open(topic, type(message))
        if channel is None:
            return
        assert isinstance(channel, _Channel) and self._sink is not None
        try:
            data = channel.encode(message)
        except Exception as exc:  # never let the recorder stop the simulation
            skipped = self._skipped.get(topic, 0)
            if not skipped:
                logger.warning("recording: cannot encode a message of %s: %s", topic, exc)
            self._skipped[topic] = skipped + 1
            return
        self._sink.write(channel.id, self._now_ns(), data)
        if channel.watch:
            self._watch(message)

    def _open(
        self, topic: str, message_type: type, encode: MessageEncoder | None = None
    ) -> _Channel | None:
        if self._patterns is not None and not any(
            fnmatch.fnmatchcase(topic, pattern) for pattern in self._patterns
        ):
            self._channels[topic] = None
            return None
        assert self._sink is not None
        encode = encode or encoder_for(message_type)
        metadata = {"armfleet_type": message_type.__name__}
        channel_id = self._sink.add_channel(topic, encode.schema, metadata)
        channel = _Channel(channel_id, encode, message_type in (BringupEvent, ArmStatus))
        self._channels[topic] = channel
        return channel

    # -- arms -------------------------------------------------------------------------
    def _watch(self, message: Any) -> None:
        if isinstance(message, BringupEvent) and message.stage is BringupStage.SPAWNED:
            self._check_arms()
            arm = self._world.arms.get(message.arm)
            if arm is not None:
                self._add_arm(arm)
        elif isinstance(message, ArmStatus):
            self._check_arms()

    def _check_arms(self) -> None:
        """Note the arms that left the world (or were replaced by a namesake)."""
        if not self._arms:
            return
        live = self._world.arms
        for name, arm in list(self._arms.items()):
            if live.get(name) is not arm:
                del self._arms[name]
                assert self._sink is not None
                self._sink.add_metadata(
                    REMOVED_METADATA, {"name": name, "removed_ns": str(self._now_ns())}
                )

    def _add_arm(self, arm: Arm) -> None:
        if self._arms.get(arm.name) is arm:
            return
        assert self._sink is not None
        now = self._now_ns()
        urdf = arm.description.urdf
        self._sink.attach(urdf_attachment(arm.name), URDF_MEDIA_TYPE, urdf.encode(), now)
        self._sink.add_metadata(ARM_METADATA, arm_metadata(arm, now))
        self._arms[arm.name] = arm
        topic = topics.robot_description(arm.name)
        channel = self._channels.get(topic, _UNSEEN)
        if channel is _UNSEEN:
            channel = self._open(topic, str, StringEncoder())
        if isinstance(channel, _Channel):
            self._sink.write(channel.id, now, channel.encode(with_file_uris(urdf)))
        self._add_meshes(arm.name, urdf, now)

    def _add_meshes(self, arm: str, urdf: str, now: int) -> None:
        """Open ``/<arm>/robot_meshes`` (the arm's visuals with their meshes inside, so
        that the file draws the arm on any machine); its message, logged at ``now``, is
        written when the file is completed: megabytes of meshes at the start would push
        the first seconds of data out of a run cut short (which has none then)."""
        topic = robot_meshes_topic(arm)
        channel = self._channels.get(topic)
        if channel is None and topic not in self._channels:
            channel = self._open(topic, dict, _ROBOT_MESHES_ENCODER)
        if isinstance(channel, _Channel):
            self._meshes.append(_PendingMeshes(arm, channel.id, urdf, now))


_UNSEEN: Any = object()


@dataclass(frozen=True)
class _PendingMeshes:
    arm: str
    channel: int
    urdf: str
    time_ns: int


def _complete(sink: McapSink, meshes: list[_PendingMeshes]) -> None:
    """Write the arms' meshes, then complete and close the file (idempotent)."""
    if sink.closed:
        return
    try:
        for pending in meshes:
            try:
                data = robot_meshes_message(pending.urdf, pending.time_ns)
            except (OSError, ValueError) as exc:
                logger.warning("recording: cannot embed the meshes of %s: %s", pending.arm, exc)
                continue
            sink.write(pending.channel, pending.time_ns, data)
        meshes.clear()
    finally:
        sink.close()


class _RobotMeshesEncoder:
    """The schema of ``/<arm>/robot_meshes`` (its messages are made whole, not encoded)."""

    schema = ROBOT_MESHES

    def __call__(self, message: Any) -> bytes:
        raise TypeError("robot meshes are written by the recorder itself")


_ROBOT_MESHES_ENCODER = _RobotMeshesEncoder()


def _is_pattern(topic: str) -> bool:
    return any(character in topic for character in "*?[")


def with_file_uris(urdf: str) -> str:
    """``urdf`` with absolute mesh paths as ``file://`` URIs (what Foxglove loads)."""
    return _MESH_PATH.sub(lambda match: f'filename="file://{match.group(1)}"', urdf)


def record(
    world: World,
    path: str | Path,
    *,
    spec: FleetSpec | None = None,
    topics: Iterable[str] | None = None,
) -> Recorder:
    """Start recording ``world`` to ``path`` (an ``.mcap`` file); stop the returned
    :class:`Recorder` (or use it in a ``with`` block) to complete the file.

    See :class:`Recorder` for the arguments.
    """
    return Recorder(world, path, spec=spec, topics=topics).start()
