"""An MCAP file being written: chunked, compressed, readable after Ctrl-C or a crash.

Memory stays bounded: messages wait in a short batch, then go into the
writer's current chunk, which is compressed and written out (and flushed to
the operating system) whenever it reaches :data:`CHUNK_BYTES`. A crash loses at
most the chunk in progress; the file up to there reads back (see
:mod:`armfleet.recording.reader`), and ``armfleet recover`` makes it complete for
other MCAP readers (:mod:`armfleet.recording.recover`). :meth:`McapSink.close`
writes the summary (index, statistics) that makes the file complete.

Every call into the writer runs with Ctrl-C held (:func:`deferred_interrupts`),
so an interrupt never leaves a half-written record behind.
"""

from __future__ import annotations

import fcntl
import io
import os
import threading
from pathlib import Path
from typing import Any

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from armfleet.checks.user_paths import file_problem
from armfleet.recording.errors import RecordingError
from armfleet.recording.interrupts import deferred_interrupts
from armfleet.recording.schemas import MessageSchema

#: Uncompressed size at which a chunk is compressed and written [bytes].
CHUNK_BYTES = 1024 * 1024
#: Messages batched before they enter the writer.
BATCH_MESSAGES = 512


def _claim(path: Path) -> io.FileIO:
    """``path`` opened empty for writing by this sink alone.

    An exclusive lock (released when the file closes) keeps a second recorder, in
    this process or another, from writing into the same file at the same time: two
    writers interleaved their records and the file read back as garbage. The file
    is emptied only once the lock is held, so a refused recorder leaves the running
    one's file intact. A FIFO or a device is no place for a recording either (opening
    a FIFO nobody reads blocked for ever).
    """
    problem = file_problem(path, missing_ok=True)
    if problem is not None:
        raise RecordingError(f"cannot write the recording {path}: it {problem}")
    try:  # not truncated yet: O_TRUNC before the lock would empty a running recorder's file
        raw = io.FileIO(os.open(path, os.O_WRONLY | os.O_CREAT, 0o666), "w")
    except OSError as exc:
        raise RecordingError(f"cannot write the recording {path}: {exc.strerror}") from None
    try:
        fcntl.flock(raw.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        raw.close()
        raise RecordingError(
            f"cannot write the recording {path}: another recorder is writing it; "
            f"stop that one or choose another file"
        ) from None
    os.ftruncate(raw.fileno(), 0)  # position is 0: nothing read or written yet
    return raw


class _FlushingFile(io.BufferedWriter):
    """A file whose every write reaches the operating system at once (one per chunk)."""

    def write(self, data: Any) -> int:
        written = super().write(data)
        self.flush()
        return written


class McapSink:
    """Writes schemas, channels, messages, attachments and metadata to one MCAP file.

    Thread-safe: messages may come from any thread.

    Args:
        path: the file to create (replaced if it exists).
        library: the writer's name in the file's header.
        chunk_bytes: uncompressed chunk size [bytes].

    Raises:
        RecordingError: the file cannot be created.
    """

    def __init__(self, path: Path, library: str, chunk_bytes: int = CHUNK_BYTES) -> None:
        self.path = path
        self._file = _FlushingFile(_claim(path))
        self._lock = threading.Lock()
        self._pending: list[tuple[int, int, bytes]] = []
        self._schemas: dict[str, int] = {}
        self._closed = False
        self.message_count = 0
        with deferred_interrupts():
            self._writer = Writer(
                self._file, chunk_size=chunk_bytes, compression=CompressionType.ZSTD
            )
            self._writer.start(profile="", library=library)

    @property
    def closed(self) -> bool:
        return self._closed

    def add_channel(self, topic: str, schema: MessageSchema, metadata: dict[str, str]) -> int:
        """Register ``topic`` with its JSON ``schema``; returns the channel id."""
        with self._lock, deferred_interrupts():
            self._write_pending()
            schema_id = self._schemas.get(schema.name)
            if schema_id is None:
                schema_id = self._writer.register_schema(
                    schema.name, SchemaEncoding.JSONSchema, schema.data
                )
                self._schemas[schema.name] = schema_id
            channel: int = self._writer.register_channel(
                topic, MessageEncoding.JSON, schema_id, metadata
            )
            return channel

    def write(self, channel: int, log_time_ns: int, data: bytes) -> None:
        """Add one message (publish time = log time); ignored once closed."""
        with self._lock:
            if self._closed:
                return
            pending = self._pending
            pending.append((channel, log_time_ns, data))
            if len(pending) >= BATCH_MESSAGES:
                with deferred_interrupts():
                    self._write_pending()

    def attach(self, name: str, media_type: str, data: bytes, log_time_ns: int) -> None:
        """Store a file (a URDF, a launch spec) in the recording."""
        with self._lock, deferred_interrupts():
            self._write_pending()
            self._writer.add_attachment(log_time_ns, log_time_ns, name, media_type, data)

    def add_metadata(self, name: str, values: dict[str, str]) -> None:
        """Store a named record of string key-values (written at once, outside any chunk)."""
        with self._lock, deferred_interrupts():
            self._write_pending()
            self._writer.add_metadata(name, values)

    def close(self) -> None:
        """Write what is pending, the last chunk and the summary; close the file. Idempotent."""
        with self._lock, deferred_interrupts():
            if self._closed:
                return
            try:
                self._write_pending()
                self._writer.finish()  # type: ignore[no-untyped-call]
            finally:
                self._closed = True
                self._file.close()

    def _write_pending(self) -> None:
        if self._closed:
            raise RecordingError(f"the recording {self.path} is closed")
        batch, self._pending = self._pending, []
        add = self._writer.add_message
        for channel, log_time, data in batch:
            add(channel, log_time, data, log_time)
        self.message_count += len(batch)
