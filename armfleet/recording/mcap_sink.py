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

import io
import threading
from pathlib import Path
from typing import Any

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from armfleet.recording.errors import RecordingError
from armfleet.recording.interrupts import deferred_interrupts
from armfleet.recording.schemas import MessageSchema

#: Uncompressed size at which a chunk is compressed and written [bytes].
CHUNK_BYTES = 1024 * 1024
#: Messages batched before they enter the writer.
BATCH_MESSAGES = 512


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
        try:
            raw = io.FileIO(path, "w")
        except OSError as exc:
            raise RecordingError(f"cannot write the recording {path}: {exc.strerror}") from None
        self._file = _FlushingFile(raw)
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
