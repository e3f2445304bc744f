"""``armfleet recover``: after ``kill -9`` the official ``mcap`` reader's default
``make_reader`` reads nothing from a recording; the recovered file is complete and indexed,
holds every message the official sequential reader gets from the original, and armfleet's
own commands accept it. ``armfleet info`` tells an unfinished file (exit 0, names
``armfleet recover``) from a damaged one (exit 2, one line)."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from mcap.exceptions import EndOfFile
from mcap.reader import NonSeekingReader, make_reader
from mcap.records import Channel, Schema
from mcap.stream_reader import StreamReader

ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")
TIMEOUT_S = 120.0
#: Written before the kill: a few 1 MiB chunks (mcap_sink.CHUNK_BYTES) [bytes].
KILL_AFTER_BYTES = 2_000_000


def armfleet(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*ARMFLEET, *args], cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S,
        env=os.environ | {"XDG_RUNTIME_DIR": str(cwd)},
    )  # fmt: skip


def default_reader_messages(path: Path) -> int:
    """Messages the official default reader yields before it ends (or gives up)."""
    count = 0
    with path.open("rb") as stream:
        try:
            for _ in make_reader(stream).iter_messages():
                count += 1
        except Exception:  # no footer to seek to: some versions raise, others yield nothing
            pass
    return count


def sequential_records(path: Path) -> list[tuple[str, int, int, bytes]]:
    """(topic, log time, publish time, data) of every message the official non-seeking
    reader gets before the file ends, in file order."""
    found: list[tuple[str, int, int, bytes]] = []
    with path.open("rb") as stream:
        reader = NonSeekingReader(stream, validate_crcs=True)
        try:
            for _, channel, message in reader.iter_messages(log_time_order=False):
                found.append((channel.topic, message.log_time, message.publish_time, message.data))
        except Exception:  # the cut (or damaged) end of the file
            pass
    return found


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@dataclass(frozen=True)
class Killed:
    """A recording whose writer got SIGKILL, and a folder to work in."""

    path: Path
    folder: Path


@pytest.fixture(scope="module")
def killed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Killed]:
    """``armfleet spawn bob --record`` in its own world, killed with SIGKILL mid-run."""
    folder = tmp_path_factory.mktemp("killed")
    path = folder / "run.mcap"
    process = subprocess.Popen(
        [*ARMFLEET, "spawn", "bob", "--at", "0,0", "--no-viewer", "--no-api", "--fast",
         "--record", str(path)],
        cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        env=os.environ | {"XDG_RUNTIME_DIR": str(folder)},
    )  # fmt: skip
    try:
        deadline = time.monotonic() + TIMEOUT_S
        while time.monotonic() < deadline and process.poll() is None:
            if path.exists() and path.stat().st_size > KILL_AFTER_BYTES:
                break
            time.sleep(0.1)
        assert process.poll() is None, process.communicate()[1]
        assert path.stat().st_size > KILL_AFTER_BYTES
    finally:
        process.kill()  # SIGKILL, to this process only
        process.communicate(timeout=TIMEOUT_S)
    assert process.returncode == -9
    yield Killed(path, folder)


def test_after_kill_9_the_default_reader_gets_nothing_and_recover_gets_everything(
    killed: Killed,
) -> None:
    before = digest(killed.path)
    expected = sequential_records(killed.path)
    assert len(expected) > 1000  # 1 MiB chunks of 1 kHz joint states, /tf and controller states
    assert default_reader_messages(killed.path) == 0  # the problem

    out = killed.folder / "out.mcap"
    result = armfleet("recover", str(killed.path), "-o", str(out), cwd=killed.folder)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("\n") == 1
    assert f"recovered {len(expected)} messages" in result.stdout
    assert "its writer did not finish" in result.stdout
    assert digest(killed.path) == before  # the source is only read

    assert default_reader_messages(out) == len(expected)
    with out.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == len(expected)
        assert len(summary.chunk_indexes) >= 2  # indexed, so seeking readers use it
        recovered = [
            (channel.topic, message.log_time, message.publish_time, message.data)
            for _, channel, message in reader.iter_messages(log_time_order=False)
        ]
        attachments = [(a.name, a.media_type, a.data) for a in reader.iter_attachments()]
        metadata = [(m.name, m.metadata) for m in reader.iter_metadata()]
    assert recovered == expected  # the same messages, bytes and times, in the same order

    source_attachments: list[tuple[str, str, bytes]] = []
    with killed.path.open("rb") as stream:  # what the source holds, read sequentially
        try:
            for a in NonSeekingReader(stream).iter_attachments():
                source_attachments.append((a.name, a.media_type, a.data))
        except EndOfFile:
            pass
    assert attachments == source_attachments
    assert "launch_spec.yaml" in [name for name, _, _ in attachments]
    source_metadata: list[tuple[str, dict[str, str]]] = []
    with killed.path.open("rb") as stream:
        try:
            for m in NonSeekingReader(stream).iter_metadata():
                source_metadata.append((m.name, m.metadata))
        except EndOfFile:
            pass
    assert metadata == source_metadata
    assert {name for name, _ in metadata} >= {"armfleet.run", "armfleet.arms.arm"}


def test_recovered_channels_and_schemas_are_the_originals(killed: Killed) -> None:
    out = killed.folder / "channels.mcap"
    assert armfleet("recover", str(killed.path), "-o", str(out), cwd=killed.folder).returncode == 0
    channels: dict[str, tuple[str, dict[str, str], str, bytes]] = {}
    schemas: dict[int, Schema] = {}
    with killed.path.open("rb") as stream:
        try:
            for record in StreamReader(stream).records:  # the official sequential reader
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel) and record.topic not in channels:
                    schema = schemas[record.schema_id]
                    channels[record.topic] = (
                        record.message_encoding,
                        dict(record.metadata),
                        schema.name,
                        schema.data,
                    )
        except EndOfFile:  # the cut end
            pass
    with out.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    written = {
        c.topic: (
            c.message_encoding,
            dict(c.metadata),
            summary.schemas[c.schema_id].name,
            summary.schemas[c.schema_id].data,
        )
        for c in summary.channels.values()
    }
    assert written == channels  # also channels that had no message before the kill


def test_info_names_recover_and_replay_and_info_accept_the_recovered_file(
    killed: Killed,
) -> None:
    info = armfleet("info", str(killed.path), cwd=killed.folder)
    assert info.returncode == 0, info.stderr
    assert "INCOMPLETE" in info.stdout
    assert f"'armfleet recover {killed.path}'" in info.stdout

    out = killed.folder / "replayable.mcap"
    assert armfleet("recover", str(killed.path), "-o", str(out), cwd=killed.folder).returncode == 0
    info = armfleet("info", str(out), cwd=killed.folder)
    assert info.returncode == 0, info.stderr
    assert "complete)" in info.stdout and "bob (panda" in info.stdout
    html = killed.folder / "replay.html"
    replay = armfleet("replay", str(out), "--html", str(html), "--quiet", cwd=killed.folder)
    assert replay.returncode == 0, replay.stderr
    assert html.stat().st_size > 0


def test_a_file_cut_inside_a_chunk_recovers_the_whole_chunks(killed: Killed) -> None:
    """Cut in the middle of the last chunk (as a full disk would): the chunks before it
    are all there, and the official sequential reader agrees on how many messages."""
    cut = killed.folder / "cut.mcap"
    data = killed.path.read_bytes()
    offset, _, length = chunks(data)[-1]
    cut.write_bytes(data[: offset + length // 2])
    expected = sequential_records(cut)
    assert len(expected) < len(sequential_records(killed.path))
    out = killed.folder / "cut-recovered.mcap"
    result = armfleet("recover", str(cut), cwd=killed.folder)  # the default output name
    assert result.returncode == 0, result.stderr
    assert f"recovered {len(expected)} messages" in result.stdout
    assert default_reader_messages(out) == len(expected) > 1000


@dataclass(frozen=True)
class BadFile:
    """Bytes made from the killed recording, and what ``info`` must say of them."""

    make: Any  # (killed recording bytes) -> bytes
    expected: tuple[str, ...]


MAGIC = b"\x89MCAP0\r\n"


def header_end(data: bytes) -> int:
    """Offset just after the Header record (opcode 1, then its uint64 length)."""
    assert data[8] == 0x01
    return 8 + 9 + int.from_bytes(data[9:17], "little")


def chunks(data: bytes) -> list[tuple[int, int, int]]:
    """(offset, opcode, body length) of each whole Chunk record, by the MCAP framing: after
    the 8-byte magic, records of a 1-byte opcode and a little-endian uint64 length."""
    found, offset = [], 8
    while offset + 9 <= len(data):
        opcode, length = data[offset], int.from_bytes(data[offset + 1 : offset + 9], "little")
        if offset + 9 + length > len(data):
            break
        if opcode == 0x06:
            found.append((offset, opcode, length))
        offset += 9 + length
    return found


def inside_second_chunk(data: bytes) -> int:
    """An offset in the middle of the second chunk's record (its compressed data)."""
    offset, _, length = chunks(data)[1]
    return offset + 9 + length // 2


def random_bytes(count: int) -> bytes:
    import random

    return random.Random(14).randbytes(count)


def flip(data: bytes, offset: int) -> bytes:
    return data[:offset] + bytes([data[offset] ^ 0xFF]) + data[offset + 1 :]


BAD_FILES = [
    pytest.param(
        BadFile(lambda d: MAGIC + random_bytes(4096), ("is damaged", "not a Header", "byte 8")),
        id="MCAP magic then random bytes -> damaged, exit 2",
    ),
    pytest.param(
        BadFile(
            lambda d: d[: header_end(d)] + random_bytes(4096),
            ("is damaged", "no message precedes it"),
        ),
        id="MCAP magic and header then random bytes -> damaged, exit 2",
    ),
    pytest.param(
        BadFile(
            lambda d: d[: chunks(d)[1][0]] + bytes(4096), ("unknown type 0x00", "armfleet recover")
        ),
        id="zeros after whole records (power loss) -> damaged, recover named",
    ),
    pytest.param(
        BadFile(
            lambda d: flip(d, inside_second_chunk(d)), ("is damaged", "CHUNK", "armfleet recover")
        ),
        id="a byte flipped inside a chunk -> damaged (CRC), recover keeps what precedes",
    ),
    pytest.param(
        BadFile(lambda d: MAGIC, ("ends before its first record",)),
        id="only the MCAP magic -> no header, exit 2",
    ),
    pytest.param(
        BadFile(lambda d: d[:12], ("ends before its first record",)),
        id="cut inside the header -> no header, exit 2",
    ),
]


@pytest.mark.parametrize("case", BAD_FILES)
def test_info_on_a_damaged_file_is_one_line_exit_2(killed: Killed, case: BadFile) -> None:
    bad = killed.folder / "bad.mcap"
    bad.write_bytes(case.make(killed.path.read_bytes()))
    result = armfleet("info", str(bad), cwd=killed.folder)
    assert result.returncode == 2, result.stdout
    assert result.stdout == ""
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("armfleet: error: ")
    assert "Traceback" not in result.stderr
    for text in case.expected:
        assert text in result.stderr, result.stderr


@pytest.fixture(scope="module")
def complete(killed: Killed) -> bytes:
    """The bytes of a complete recording (the killed one, recovered)."""
    out = killed.folder / "complete.mcap"
    assert armfleet("recover", str(killed.path), "-o", str(out), cwd=killed.folder).returncode == 0
    return out.read_bytes()


def test_a_complete_file_whose_index_points_nowhere_is_damaged(
    killed: Killed, complete: bytes
) -> None:
    """The summary reads, but the first chunk it names is not there: info says so."""
    offset = chunks(complete)[0][0]
    bad = killed.folder / "bad-index.mcap"
    bad.write_bytes(flip(complete, offset))  # the chunk's opcode byte
    result = armfleet("info", str(bad), cwd=killed.folder)
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.count("\n") == 1
    assert f"is damaged: its index names a chunk at byte {offset}, where none is" in result.stderr


def test_a_complete_file_with_a_bad_chunk_is_refused_when_read(
    killed: Killed, complete: bytes
) -> None:
    """A byte flipped in compressed data passes the index check; reading the messages
    (replay, plot) meets it and stops with one line, naming recover."""
    bad = killed.folder / "bad-chunk.mcap"
    bad.write_bytes(flip(complete, inside_second_chunk(complete)))
    html = killed.folder / "bad-chunk.html"
    result = armfleet("replay", str(bad), "--html", str(html), "--quiet", cwd=killed.folder)
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert "is damaged: a chunk cannot be read" in result.stderr
    assert f"'armfleet recover {bad}' saves the messages before it" in result.stderr


def test_recover_keeps_what_precedes_damage(killed: Killed) -> None:
    """A flipped byte in the second chunk: the messages of the first are saved, as many as
    the official reader (checking CRCs) yields before it fails."""
    bad = killed.folder / "flipped.mcap"
    data = killed.path.read_bytes()
    bad.write_bytes(flip(data, inside_second_chunk(data)))
    expected = sequential_records(bad)
    assert 0 < len(expected) < len(sequential_records(killed.path))
    out = killed.folder / "flipped-saved.mcap"
    result = armfleet("recover", str(bad), "-o", str(out), cwd=killed.folder)
    assert result.returncode == 0, result.stderr
    assert "it is damaged" in result.stdout
    assert default_reader_messages(out) == len(expected)


BAD_RECOVERIES = [
    pytest.param(["{missing}"], "no recording at {missing}", id="no such file -> not found"),
    pytest.param(["{notes}"], "is not an MCAP recording", id="a text file -> not MCAP"),
    pytest.param(["{run}", "-o", "{tmp}/out.bag"], "name a .mcap file", id="-o not .mcap"),
    pytest.param(["{run}", "-o", "{run}"], "is the file being recovered", id="-o the source"),
    pytest.param(
        ["{run}", "-o", "{notes}.mcap"],
        "exists; name a new file",
        id="-o an existing file -> refused, not overwritten",
    ),
    pytest.param(
        ["{run}", "-o", "{tmp}/no/such/out.mcap"], "does not exist", id="-o in a missing folder"
    ),
    pytest.param(
        ["{garbage}"],
        "there is nothing to recover",
        id="magic, header and random bytes -> nothing to recover",
    ),
    pytest.param([], "the following arguments are required: RUN.mcap", id="no file given"),
]


def files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.is_file())


@pytest.mark.parametrize(("args", "expected"), BAD_RECOVERIES)
def test_bad_recover_is_one_line_exit_2_and_writes_nothing(
    killed: Killed, tmp_path: Path, args: list[str], expected: str
) -> None:
    notes = tmp_path / "notes.txt"
    notes.write_text("not a recording\n")
    (tmp_path / "notes.txt.mcap").write_text("already here\n")
    garbage = tmp_path / "garbage.mcap"
    data = killed.path.read_bytes()
    garbage.write_bytes(data[: header_end(data)] + random_bytes(4096))
    values = {
        "missing": str(tmp_path / "missing.mcap"),
        "notes": str(notes),
        "run": str(killed.path),
        "garbage": str(garbage),
        "tmp": str(tmp_path),
    }
    before = files(tmp_path)
    source = digest(killed.path)
    result = armfleet("recover", *[a.format(**values) for a in args], cwd=tmp_path)
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("armfleet: error: ")
    assert expected.format(**values) in result.stderr
    assert files(tmp_path) == before  # no output, no temporary file left
    assert (tmp_path / "notes.txt.mcap").read_text() == "already here\n"
    assert digest(killed.path) == source
