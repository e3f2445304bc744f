"""The per-user runtime file that tells clients where the running world listens.

``$XDG_RUNTIME_DIR/armfleet/world.json`` (or ``~/.cache/armfleet/world.json``),
mode 0600 in a 0700 folder, holds the address and the process of the world that
serves it, and when it started serving. A file whose process is gone is stale and
ignored.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

FILE_NAME = "world.json"


def runtime_folder() -> Path:
    """``$XDG_RUNTIME_DIR/armfleet`` if that folder exists, else ``~/.cache/armfleet``."""
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and Path(runtime).is_dir():
        return Path(runtime) / "armfleet"
    cache = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(cache) / "armfleet"


def runtime_path() -> Path:
    return runtime_folder() / FILE_NAME


@dataclass(frozen=True)
class WorldEntry:
    """What the runtime file says.

    Attributes:
        address: ``tcp://HOST:PORT`` of the world's API.
        pid: process serving it.
        started: start time of that process (clock ticks since boot; 0 if unknown),
            so that a recycled pid is not mistaken for the world.
        path: the file it was read from.
        since: when the world started serving [s since the epoch]; None in a file
            written before it was recorded.
    """

    address: str
    pid: int
    started: int
    path: Path
    since: float | None = None

    @property
    def alive(self) -> bool:
        return process_alive(self.pid, self.started)

    @property
    def started_at(self) -> float | None:
        """When the world started [s since the epoch]: :attr:`since`, else its process's
        start; None if neither is known."""
        if self.since is not None:
            return self.since
        return process_start_time(self.started)


def process_start(pid: int) -> int:
    """Start time of process ``pid`` in clock ticks since boot (0 where /proc has none)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0
    # Field 22, counted after the parenthesised command name (which may hold spaces).
    fields = stat[stat.rfind(")") + 2 :].split()
    return int(fields[19]) if len(fields) > 19 and fields[19].isdigit() else 0


def process_start_time(started: int) -> float | None:
    """A process start in clock ticks since boot (see :func:`process_start`) as seconds
    since the epoch; None if unknown."""
    try:
        boot = next(
            int(line.split()[1])
            for line in Path("/proc/stat").read_text().splitlines()
            if line.startswith("btime ")
        )
    except (OSError, StopIteration, ValueError, IndexError):
        return None
    return boot + started / os.sysconf("SC_CLK_TCK") if started else None


def process_alive(pid: int, started: int = 0) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # exists, another user's
    return not started or process_start(pid) in (0, started)


def read_entry(path: Path | None = None) -> WorldEntry | None:
    """The world the runtime file names, or None (no file, unreadable, malformed)."""
    path = path or runtime_path()
    try:
        data = json.loads(path.read_text())
        since = data.get("since")
        if not (isinstance(since, int | float) and math.isfinite(since)):
            since = None
        return WorldEntry(
            str(data["address"]), int(data["pid"]), int(data.get("started", 0)), path, since
        )
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def live_entry(path: Path | None = None) -> WorldEntry | None:
    """The runtime file's world if its process still runs; None otherwise."""
    entry = read_entry(path)
    return entry if entry is not None and entry.alive else None


def write_entry(address: str, path: Path | None = None) -> Path | None:
    """Name this process's world in the runtime file, unless another live world holds it.

    Returns:
        The file written, or None when another running world already holds it.
    """
    path = path or runtime_path()
    holder = live_entry(path)
    if holder is not None and holder.pid != os.getpid():
        return None
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    pid = os.getpid()
    text = json.dumps(
        {"address": address, "pid": pid, "started": process_start(pid), "since": time.time()}
    )
    temporary = path.with_name(f".{path.name}.{pid}")
    descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "w") as stream:
        stream.write(text + "\n")
    os.replace(temporary, path)
    return path


def remove_entry(path: Path) -> None:
    """Remove the runtime file if it still names this process."""
    entry = read_entry(path)
    if entry is not None and entry.pid == os.getpid():
        with contextlib.suppress(OSError):
            path.unlink()
