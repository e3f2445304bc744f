"""A linear scan of an MCAP file from its start that tells a cut tail from damage.

A writer killed mid-run (``kill -9``, a crash, a full disk) leaves a file whose
records are all whole up to the last one written, which the end of the file may
cut; there is no summary and no footer. Anything else that breaks the record
structure is damage: a first record that is not a Header, an opcode MCAP does
not define, a record claiming more than :data:`MAX_RECORD_BYTES`, a body its
type cannot be read from, a chunk whose compression or CRC is wrong, bytes
after the footer. Random bytes after an MCAP magic fail at their first record
(the length they claim is almost surely beyond any real record).

The record bodies are read by the ``mcap`` package's own record classes and
chunk reader (:func:`mcap.stream_reader.breakup_chunk`, CRCs checked); this
module only frames them, so that where the file ends decides "cut" and nothing
else does.
"""

from __future__ import annotations

import enum
import io
import struct
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    McapRecord,
    Message,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.stream_reader import breakup_chunk

MCAP_MAGIC = b"\x89MCAP0\r\n"
#: Largest record believed [bytes]: the ``mcap`` readers' own default limit (4 GiB).
MAX_RECORD_BYTES = 4 * 2**30
#: Opcodes from 0x80 up are private records (MCAP spec): skipped, not damage.
FIRST_PRIVATE_OPCODE = 0x80
_RECORD_HEAD = struct.Struct("<BQ")  # opcode, body length [bytes]
_RECORD_TYPES: dict[int, Any] = {
    Opcode.ATTACHMENT: Attachment,
    Opcode.ATTACHMENT_INDEX: AttachmentIndex,
    Opcode.CHANNEL: Channel,
    Opcode.CHUNK: Chunk,
    Opcode.CHUNK_INDEX: ChunkIndex,
    Opcode.DATA_END: DataEnd,
    Opcode.FOOTER: Footer,
    Opcode.HEADER: Header,
    Opcode.MESSAGE_INDEX: MessageIndex,
    Opcode.METADATA: Metadata,
    Opcode.METADATA_INDEX: MetadataIndex,
    Opcode.SCHEMA: Schema,
    Opcode.STATISTICS: Statistics,
    Opcode.SUMMARY_OFFSET: SummaryOffset,
}


class FileEnd(enum.Enum):
    """How the records of a file end."""

    #: A footer and the closing magic: the writer finished.
    COMPLETE = "complete"
    #: Whole records, then the end of the file (perhaps inside a record): the writer died.
    CUT = "cut"
    #: Something that no MCAP writer writes.
    DAMAGED = "damaged"


@dataclass(frozen=True)
class ScanResult:
    """Where and how a scan ended.

    Attributes:
        end: how the records end.
        offset: bytes of whole, readable records from the start of the file (magic included).
        reason: what is wrong at ``offset`` (empty unless DAMAGED).
        has_header: whether the first record, a Header, was read.
        message_count: messages read before ``offset``.
    """

    end: FileEnd
    offset: int
    reason: str
    has_header: bool
    message_count: int


class RecordScan:
    """The records of the MCAP file at ``path``, in file order, chunks opened.

    Iterate once; then :attr:`result` says how the file ended. Iteration stops at
    the first cut or damaged record without raising.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.result: ScanResult | None = None

    def __iter__(self) -> Iterator[McapRecord]:
        with self.path.open("rb") as stream:
            self.result = yield from _walk(stream)


def _walk(stream: BinaryIO) -> Generator[McapRecord, None, ScanResult]:
    """Yield the records of ``stream`` from its start; return how its records end."""
    stream.seek(0, io.SEEK_END)
    size = stream.tell()
    stream.seek(0)
    messages, offset, has_header = 0, 0, False

    def end(how: FileEnd, reason: str = "") -> ScanResult:
        return ScanResult(how, offset, reason, has_header, messages)

    if stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
        return end(FileEnd.DAMAGED, "it does not start with the MCAP magic bytes")
    offset = len(MCAP_MAGIC)
    while True:
        head = stream.read(_RECORD_HEAD.size)
        if len(head) < _RECORD_HEAD.size:
            return end(FileEnd.CUT)
        opcode, length = _RECORD_HEAD.unpack(head)
        problem = _implausible(opcode, length, has_header)
        if problem:
            return end(FileEnd.DAMAGED, f"{problem} at byte {offset}")
        if offset + _RECORD_HEAD.size + length > size:
            return end(FileEnd.CUT)
        body = stream.read(length)
        try:
            records = _records_of(opcode, length, body)
        except Exception as exc:  # any failure to read a whole body is damage
            reason = f"unreadable {_opcode_name(opcode)} record at byte {offset}"
            return end(FileEnd.DAMAGED, f"{reason} ({type(exc).__name__}: {exc})")
        for record in records:
            messages += isinstance(record, Message)
            yield record
        has_header = True
        offset += _RECORD_HEAD.size + length
        if opcode == Opcode.FOOTER:
            if stream.read(len(MCAP_MAGIC) + 1) != MCAP_MAGIC:
                reason = f"the footer ending at byte {offset} is not followed by the closing "
                return end(FileEnd.DAMAGED, reason + "magic and the end of the file")
            offset = size
            return end(FileEnd.COMPLETE)


def _implausible(opcode: int, length: int, has_header: bool) -> str:
    """Why a record head cannot be from an MCAP writer ("" if it can)."""
    if not has_header and opcode != Opcode.HEADER:
        return f"the first record is not a Header (opcode 0x{opcode:02x})"
    known = opcode in _RECORD_TYPES or opcode == Opcode.MESSAGE
    if not known and opcode < FIRST_PRIVATE_OPCODE:
        return f"a record of unknown type 0x{opcode:02x}"
    if length > MAX_RECORD_BYTES:
        return f"a {_opcode_name(opcode)} record claiming {length:,} bytes"
    return ""


def _records_of(opcode: int, length: int, body: bytes) -> list[McapRecord]:
    """The record in ``body`` (a chunk's records for a chunk; nothing for a private one)."""
    stream = ReadDataStream(io.BytesIO(body))
    if opcode == Opcode.MESSAGE:
        return [Message.read(stream, length)]
    record_type = _RECORD_TYPES.get(opcode)
    if record_type is None:
        return []
    record: McapRecord = record_type.read(stream)
    if isinstance(record, Chunk):
        return breakup_chunk(record, validate_crc=True)
    return [record]


def _opcode_name(opcode: int) -> str:
    try:
        return Opcode(opcode).name
    except ValueError:
        return f"0x{opcode:02x}"
