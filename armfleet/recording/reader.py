"""Read an MCAP recording: its topics, arms, launch spec and messages.

A complete file is read through its summary (index and statistics). A file
whose writer died (a crash, ``kill -9``) has no summary: it is then scanned from
the start, and everything up to the last whole record is there;
:attr:`Recording.complete` tells which (``armfleet recover`` writes a complete
copy). A file broken in any other way (random bytes, a bad chunk) is refused with
:class:`DamagedRecording` rather than read as far as it happens to go; see
:mod:`armfleet.recording.record_scan` for the line between the two.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcap.opcode import Opcode
from mcap.reader import SeekingReader
from mcap.records import Attachment, Channel, Message, Metadata, Schema
from mcap.summary import Summary
from mcap.well_known import MessageEncoding

from armfleet.checks.user_paths import file_problem, given_path
from armfleet.recording.arm_record import (
    ARM_METADATA,
    REMOVED_METADATA,
    RUN_METADATA,
    ArmRecord,
    arm_record,
)
from armfleet.recording.errors import (
    DamagedRecording,
    NotARecording,
    RecordingError,
    RecordingNotFound,
    UnknownRecordedArm,
)
from armfleet.recording.record_scan import MCAP_MAGIC, FileEnd, RecordScan, ScanResult
from armfleet.recording.recorder import SPEC_ATTACHMENT

NS_PER_S = 1e9
CHUNK_OPCODE = bytes([Opcode.CHUNK])


@dataclass(frozen=True)
class TopicInfo:
    """One recorded topic.

    Attributes:
        topic: topic name.
        schema_name: its messages' schema, e.g. ``sensor_msgs/msg/JointState``.
        message_type: armfleet's message class name, e.g. ``JointState`` ("" if unknown).
        encoding: message encoding (``json`` for armfleet's recordings).
        message_count: messages in the file.
    """

    topic: str
    schema_name: str
    message_type: str
    encoding: str
    message_count: int


@dataclass(frozen=True)
class RecordedMessage:
    """One message read back.

    Attributes:
        topic: its topic.
        log_time_ns: simulated time at which it was published [ns].
        data: the decoded JSON message.
    """

    topic: str
    log_time_ns: int
    data: Any

    @property
    def time_s(self) -> float:
        """Simulated time [s]."""
        return self.log_time_ns / NS_PER_S


@dataclass
class _Contents:
    """What a linear scan or the summary tells about a file."""

    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    counts: dict[int, int]
    start_ns: int | None
    end_ns: int | None
    attachments: list[Attachment]
    metadata: list[Metadata]


def open_recording(path: str | Path) -> Recording:
    """Open the recording at ``path``.

    Raises:
        RecordingNotFound: no such file.
        NotARecording: the file is not an MCAP file.
    """
    return Recording(path)


class Recording:
    """An MCAP recording, opened for reading (see :func:`open_recording`)."""

    def __init__(self, path: str | Path) -> None:
        self.path = given_path(path, "recording")
        _check_magic(self.path)
        self._summary = self._read_summary()
        #: Whether the file ends with its summary (False: the writer died; read up to the
        #: last complete chunk).
        self.complete = self._summary is not None
        self.truncated = False
        contents = self._from_summary(self._summary) if self._summary else self._scan()
        self._channels = contents.channels
        self._topic_channels = {c.topic: c for c in contents.channels.values()}
        self.start_ns = contents.start_ns
        self.end_ns = contents.end_ns
        self.topics: dict[str, TopicInfo] = {}
        for channel_id, channel in sorted(contents.channels.items()):
            schema = contents.schemas.get(channel.schema_id)
            self.topics[channel.topic] = TopicInfo(
                channel.topic,
                schema.name if schema else "",
                channel.metadata.get("armfleet_type", ""),
                channel.message_encoding,
                contents.counts.get(channel_id, 0),
            )
        self.run = _last_metadata(contents.metadata, RUN_METADATA)
        self.arms = _arms(contents.metadata, contents.attachments, self.path)
        self.spec_text = _spec_text(contents.attachments)
        self.attachment_names = tuple(a.name for a in contents.attachments)

    # -- what is in it ----------------------------------------------------------------
    @property
    def message_count(self) -> int:
        return sum(info.message_count for info in self.topics.values())

    @property
    def duration_s(self) -> float:
        """Simulated time from the first to the last message [s]."""
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / NS_PER_S

    @property
    def arm_names(self) -> tuple[str, ...]:
        """Names of the recorded arms, in spawn order (each once)."""
        return tuple(dict.fromkeys(arm.name for arm in self.arms))

    def arm(self, name: str) -> ArmRecord:
        """The last arm recorded under ``name``.

        Raises:
            UnknownRecordedArm: no such arm.
        """
        for arm in reversed(self.arms):
            if arm.name == name:
                return arm
        raise UnknownRecordedArm(self.path, name, self.arm_names)

    # -- messages ---------------------------------------------------------------------
    def raw_messages(self, topics: Iterable[str] | None = None) -> Iterator[tuple[str, int, bytes]]:
        """``(topic, log time [ns], encoded message)`` in log-time order, undecoded."""
        wanted = None if topics is None else set(topics)
        if self._summary is not None:
            with self.path.open("rb") as stream:
                reader = SeekingReader(stream, validate_crcs=True)
                try:
                    for _, channel, message in reader.iter_messages(topics=wanted):
                        yield channel.topic, message.log_time, message.data
                except Exception as exc:  # a chunk the summary points at cannot be read
                    reason = f"a chunk cannot be read ({type(exc).__name__}: {exc})"
                    raise DamagedRecording(self.path, reason, None) from None
            return
        channels: dict[int, Channel] = {}
        for record in RecordScan(self.path):
            if isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                defined = channels.get(record.channel_id)
                if defined is None:
                    raise DamagedRecording(
                        self.path, f"a message on channel {record.channel_id}, never defined", 0
                    )
                if wanted is None or defined.topic in wanted:
                    yield defined.topic, record.log_time, record.data

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[RecordedMessage]:
        """The messages of ``topics`` (all if None), decoded, in log-time order.

        Raises:
            RecordingError: a topic's messages are not JSON, or a message is malformed.
        """
        if topics is not None:
            topics = list(topics)
            for topic in topics:
                self._check_json(topic)
        for topic, log_time, data in self.raw_messages(topics):
            yield RecordedMessage(topic, log_time, self.decode(topic, data))

    def decode(self, topic: str, data: bytes) -> Any:
        """One message of ``topic`` from its encoded bytes."""
        try:
            return json.loads(data)
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise RecordingError(f"{self.path}: a message of {topic} is not JSON ({exc})") from None

    def _check_json(self, topic: str) -> None:
        channel = self._topic_channels.get(topic)
        if channel is not None and channel.message_encoding != MessageEncoding.JSON:
            raise RecordingError(
                f"{self.path}: {topic} is encoded as {channel.message_encoding!r}; "
                "armfleet reads JSON recordings"
            )

    # -- reading the file -------------------------------------------------------------
    def _read_summary(self) -> Summary | None:
        try:
            with self.path.open("rb") as stream:
                return SeekingReader(stream).get_summary()
        except Exception:  # no footer: the writer did not finish (the scan reads the rest)
            return None

    def _from_summary(self, summary: Summary) -> _Contents:
        _check_chunk_index(self.path, summary)
        statistics = summary.statistics
        with self.path.open("rb") as stream:
            reader = SeekingReader(stream)
            attachments = list(reader.iter_attachments())
            metadata = list(reader.iter_metadata())
        counts = dict(statistics.channel_message_counts) if statistics else {}
        has_messages = statistics is not None and statistics.message_count > 0
        return _Contents(
            schemas=dict(summary.schemas),
            channels=dict(summary.channels),
            counts=counts,
            start_ns=statistics.message_start_time if has_messages and statistics else None,
            end_ns=statistics.message_end_time if has_messages and statistics else None,
            attachments=attachments,
            metadata=metadata,
        )

    def _scan(self) -> _Contents:
        contents = _Contents({}, {}, {}, None, None, [], [])
        scan = RecordScan(self.path)
        for record in scan:
            if isinstance(record, Message):
                contents.counts[record.channel_id] = contents.counts.get(record.channel_id, 0) + 1
                time = record.log_time
                if contents.start_ns is None or time < contents.start_ns:
                    contents.start_ns = time
                if contents.end_ns is None or time > contents.end_ns:
                    contents.end_ns = time
            elif isinstance(record, Schema):
                contents.schemas[record.id] = record
            elif isinstance(record, Channel):
                contents.channels[record.id] = record
            elif isinstance(record, Attachment):
                contents.attachments.append(record)
            elif isinstance(record, Metadata):
                contents.metadata.append(record)
        result = scan.result
        assert result is not None  # the scan has ended
        _refuse_damage(self.path, result)
        self.truncated = True
        return contents

    def __repr__(self) -> str:
        state = "complete" if self.complete else "incomplete"
        return (
            f"Recording({str(self.path)!r}, {state}, {len(self.topics)} topics, "
            f"{self.message_count} messages, {self.duration_s:.3f} s, arms={list(self.arm_names)})"
        )


def _check_magic(path: Path) -> None:
    problem = file_problem(path, missing_ok=True)
    if problem is not None:
        # Opening a FIFO nobody writes to waits for ever; a device is no recording either.
        raise NotARecording(path, f"it {problem}")
    try:
        with path.open("rb") as stream:
            head = stream.read(len(MCAP_MAGIC))
    except FileNotFoundError:
        raise RecordingNotFound(path) from None
    except IsADirectoryError:
        raise NotARecording(path, "it is a directory") from None
    except OSError as exc:
        raise RecordingError(f"cannot read {path}: {exc.strerror}") from None
    if not head:
        raise NotARecording(path, "the file is empty")
    if head != MCAP_MAGIC:
        raise NotARecording(path, "it does not start with the MCAP magic bytes")


def _check_chunk_index(path: Path, summary: Summary) -> None:
    """Raise DamagedRecording unless every chunk the index names starts where it says
    (one byte read per chunk: it catches a mangled index or data section, not a byte
    flipped inside a chunk's compressed data, which reading the messages finds)."""
    size = path.stat().st_size
    with path.open("rb") as stream:
        for index in summary.chunk_indexes:
            start, length = index.chunk_start_offset, index.chunk_length
            stream.seek(start)
            if start + length > size or stream.read(1) != CHUNK_OPCODE:
                reason = f"its index names a chunk at byte {start}, where none is"
                raise DamagedRecording(path, reason, None)


def _refuse_damage(path: Path, result: ScanResult) -> None:
    """Raise DamagedRecording unless the scan ended as a killed writer's file ends."""
    if result.end is FileEnd.DAMAGED:
        raise DamagedRecording(path, result.reason, result.message_count)
    if not result.has_header:
        raise DamagedRecording(path, "it ends before its first record (the Header)", 0)


def _last_metadata(metadata: list[Metadata], name: str) -> dict[str, str]:
    found = [m.metadata for m in metadata if m.name == name]
    return dict(found[-1]) if found else {}


def _arms(
    metadata: list[Metadata], attachments: list[Attachment], path: Path
) -> tuple[ArmRecord, ...]:
    """The arms, from their metadata records in the order they were written."""
    urdfs = {(a.name, a.log_time): a.data for a in attachments}
    arms: list[ArmRecord] = []
    live: dict[str, int] = {}  # name -> index in arms
    for record in metadata:
        values = dict(record.metadata)
        try:
            if record.name == ARM_METADATA:
                spawned = int(values.get("spawned_ns", ""))
                urdf = urdfs.get((values.get("urdf_attachment", ""), spawned), b"")
                arm = arm_record(values, urdf.decode("utf-8", errors="replace"), None)
                if arm.name in live:  # replaced by a namesake without a removal noted
                    index = live[arm.name]
                    arms[index] = dataclasses.replace(arms[index], removed_ns=spawned)
                live[arm.name] = len(arms)
                arms.append(arm)
            elif record.name == REMOVED_METADATA and values.get("name") in live:
                index = live.pop(values["name"])
                removed = int(values["removed_ns"])
                arms[index] = dataclasses.replace(arms[index], removed_ns=removed)
        except (KeyError, ValueError) as exc:
            raise RecordingError(f"{path}: malformed {record.name} record ({exc})") from None
    return tuple(arms)


def _spec_text(attachments: list[Attachment]) -> str | None:
    for attachment in attachments:
        if attachment.name == SPEC_ATTACHMENT:
            return attachment.data.decode("utf-8", errors="replace")
    return None
