"""``armfleet recover``: a complete, indexed MCAP file from one whose writer died.

After ``kill -9`` a recording has every chunk written up to the kill but no
summary or footer. The ``mcap`` package's default reader
(``make_reader(f).iter_messages()``) seeks to the footer and finds none, so it
reads nothing; only a sequential reader gets the messages back. Like the mcap
CLI's ``recover``, this reads the file from the start
(:class:`~armfleet.recording.record_scan.RecordScan`, the ``mcap`` package's own
record classes) and writes every whole record again with the ``mcap`` package's
:class:`~mcap.writer.Writer`: the Header's profile and library, schemas, channels
(also those with no message yet), messages, attachments (URDFs, the launch spec)
and metadata (the run, the arms). The writer adds the chunk and message indexes,
statistics and summary.

A file damaged in the middle gives everything before the damage. The new file is
written beside the output under a temporary name and renamed when finished, so
an interrupted recovery leaves no half-written output behind, and the source is
only ever read.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from mcap.records import Attachment, Channel, Header, Message, Metadata, Schema
from mcap.writer import CompressionType, Writer

from armfleet.checks.user_paths import file_problem, given_path
from armfleet.recording.errors import (
    DamagedRecording,
    NotARecording,
    RecordingError,
    RecordingNotFound,
)
from armfleet.recording.mcap_sink import CHUNK_BYTES
from armfleet.recording.record_scan import MCAP_MAGIC, FileEnd, RecordScan


@dataclass(frozen=True)
class Recovery:
    """What a recovery kept.

    Attributes:
        source: the file read.
        output: the complete file written.
        end: how the source ended (COMPLETE: it needed no recovery; CUT: its writer
            died; DAMAGED: it breaks off in damage, see ``reason``).
        reason: what is wrong where the source's readable records end ("" unless DAMAGED).
        source_bytes: size of the source [bytes].
        kept_bytes: bytes of whole records read from it [bytes].
        messages, channels, schemas, attachments, metadata: records written.
    """

    source: Path
    output: Path
    end: FileEnd
    reason: str
    source_bytes: int
    kept_bytes: int
    messages: int
    channels: int
    schemas: int
    attachments: int
    metadata: int

    @property
    def records_after_header(self) -> int:
        """Schemas, channels, messages, attachments and metadata records kept."""
        return self.schemas + self.channels + self.messages + self.attachments + self.metadata

    def describe(self) -> str:
        """One line for the CLI."""
        how = {
            FileEnd.COMPLETE: "it was complete already",
            FileEnd.CUT: "its writer did not finish",
            FileEnd.DAMAGED: f"it is damaged: {self.reason}",
        }[self.end]
        return (
            f"recovered {self.messages} messages on {self.channels} channels, "
            f"{self.attachments} attachments and {self.metadata} metadata records "
            f"({self.kept_bytes} of {self.source_bytes} bytes; {how}) into {self.output}"
        )


def default_output(source: Path) -> Path:
    """``RUN.mcap`` -> ``RUN-recovered.mcap`` beside it."""
    return source.with_name(f"{source.stem}-recovered.mcap")


def recover(source: str | Path, output: str | Path | None = None) -> Recovery:
    """Write the whole records of ``source`` into a complete, indexed MCAP ``output``.

    Args:
        source: an MCAP file, usually one whose writer died.
        output: the file to write (default :func:`default_output`); must end in
            ``.mcap``, be in an existing folder, and not exist yet.

    Raises:
        RecordingNotFound: no file at ``source``.
        NotARecording: ``source`` is not an MCAP file.
        DamagedRecording: ``source`` is cut or damaged before any record after its
            Header (nothing to recover).
        RecordingError: ``output`` is unusable, or cannot be written.
    """
    source = given_path(source, "recording")
    target = default_output(source) if output is None else given_path(output, "output")
    _check_paths(source, target)
    folder = target.parent
    handle, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=folder)
    try:
        with os.fdopen(handle, "wb") as stream:
            recovery = _copy(source, stream, target)
        if recovery.end is not FileEnd.COMPLETE and not recovery.records_after_header:
            reason = recovery.reason or "it ends before any record after its Header"
            raise DamagedRecording(source, f"{reason}; there is nothing to recover", 0)
        _publish(Path(temporary), target)
    except FileExistsError:
        raise RecordingError(f"{target} appeared while recovering; nothing replaced") from None
    except OSError as exc:
        raise RecordingError(f"cannot write {target}: {exc.strerror}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
    return recovery


def _publish(finished: Path, target: Path) -> None:
    """Give the finished file its name, never replacing a file that appeared meanwhile."""
    try:
        os.link(finished, target)  # raises FileExistsError rather than replacing
    except FileExistsError:
        raise
    except OSError:  # a file system without hard links: check, then rename
        if target.exists():
            raise FileExistsError(target) from None
        os.replace(finished, target)


def _check_paths(source: Path, target: Path) -> None:
    if not source.exists():
        raise RecordingNotFound(source)
    problem = file_problem(source)
    if problem is not None:
        raise NotARecording(source, f"it {problem}")
    with source.open("rb") as stream:
        if stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise NotARecording(source, "it does not start with the MCAP magic bytes")
    if target.suffix != ".mcap":
        raise RecordingError(f"-o {target}: name a .mcap file")
    if not target.parent.is_dir():
        raise RecordingError(f"-o {target}: the folder {target.parent} does not exist")
    if target.exists():
        same = target.resolve() == source.resolve()
        what = "is the file being recovered" if same else "exists"
        raise RecordingError(f"-o {target}: {what}; name a new file")


def _copy(source: Path, stream: IO[bytes], target: Path) -> Recovery:
    writer = Writer(stream, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
    schema_ids: dict[int, int] = {}  # source id -> output id (0: no schema)
    channel_ids: dict[int, int] = {}
    counts = {"messages": 0, "attachments": 0, "metadata": 0}
    scan = RecordScan(source)
    started = False
    for record in scan:
        if isinstance(record, Header):
            writer.start(profile=record.profile, library=record.library)
            started = True
        elif isinstance(record, Schema) and record.id not in schema_ids:
            schema_ids[record.id] = writer.register_schema(
                record.name, record.encoding, record.data
            )
        elif isinstance(record, Channel) and record.id not in channel_ids:
            channel_ids[record.id] = writer.register_channel(
                record.topic,
                record.message_encoding,
                schema_ids.get(record.schema_id, 0),
                dict(record.metadata),
            )
        elif isinstance(record, Message) and record.channel_id in channel_ids:
            writer.add_message(
                channel_ids[record.channel_id],
                record.log_time,
                record.data,
                record.publish_time,
                record.sequence,
            )
            counts["messages"] += 1
        elif isinstance(record, Attachment):
            writer.add_attachment(
                record.create_time, record.log_time, record.name, record.media_type, record.data
            )
            counts["attachments"] += 1
        elif isinstance(record, Metadata):
            writer.add_metadata(record.name, dict(record.metadata))
            counts["metadata"] += 1
    if started:
        writer.finish()  # type: ignore[no-untyped-call]
    result = scan.result
    assert result is not None  # the scan has ended
    return Recovery(
        source=source,
        output=target,
        end=result.end,
        reason=result.reason,
        source_bytes=source.stat().st_size,
        kept_bytes=result.offset,
        messages=counts["messages"],
        channels=len(channel_ids),
        schemas=len(schema_ids),
        attachments=counts["attachments"],
        metadata=counts["metadata"],
    )
