"""The runtime file that lets clients find the running world: private, and never stale."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from armfleet.remote import NoWorldFound, runtime_file
from armfleet.remote.client import find_world

ADDRESS = "tcp://127.0.0.1:5555"


@pytest.fixture
def runtime(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    return tmp_path / "armfleet" / "world.json"


@pytest.fixture
def other_process() -> Iterator[subprocess.Popen[bytes]]:
    """A live process that is not this one (a world run by someone else)."""
    process = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    yield process
    process.kill()
    process.wait()


def ended_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def write(path: Path, pid: int, started: int = 0) -> None:
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    path.write_text(json.dumps({"address": "tcp://127.0.0.1:1", "pid": pid, "started": started}))


def test_the_file_is_private_and_names_this_process(runtime: Path) -> None:
    assert runtime_file.write_entry(ADDRESS) == runtime
    assert stat.S_IMODE(runtime.stat().st_mode) == 0o600
    assert stat.S_IMODE(runtime.parent.stat().st_mode) == 0o700
    entry = runtime_file.live_entry()
    assert entry is not None and (entry.address, entry.pid) == (ADDRESS, os.getpid())
    assert find_world() == (ADDRESS, f"named by {runtime}, process {os.getpid()}")
    runtime_file.remove_entry(runtime)
    assert not runtime.exists()


def test_a_file_whose_process_has_ended_is_ignored_and_replaced(runtime: Path) -> None:
    pid = ended_pid()
    write(runtime, pid)
    assert runtime_file.live_entry() is None
    with pytest.raises(NoWorldFound, match=f"names process {pid}, which has ended"):
        find_world()
    assert runtime_file.write_entry(ADDRESS) == runtime
    assert json.loads(runtime.read_text())["pid"] == os.getpid()


def test_a_recycled_pid_is_not_mistaken_for_the_world(runtime: Path) -> None:
    started = runtime_file.process_start(os.getpid())
    if not started:
        pytest.skip("no /proc here: process start times are unknown")
    write(runtime, os.getpid(), started + 1)  # this pid, but a process started at another time
    assert runtime_file.live_entry() is None


def test_a_running_world_keeps_the_file_and_others_leave_it_alone(
    runtime: Path, other_process: subprocess.Popen[bytes]
) -> None:
    write(runtime, other_process.pid, runtime_file.process_start(other_process.pid))
    assert runtime_file.write_entry(ADDRESS) is None  # another world is the default
    runtime_file.remove_entry(runtime)  # not ours to remove
    entry = runtime_file.live_entry()
    assert entry is not None and entry.pid == other_process.pid


def test_no_file_or_a_malformed_one_means_no_world(runtime: Path) -> None:
    with pytest.raises(NoWorldFound, match=r"no running world found .*armfleet spawn bob"):
        find_world()
    runtime.parent.mkdir(parents=True)
    runtime.write_text("{not json")
    assert runtime_file.read_entry() is None


def test_without_a_runtime_folder_the_file_lives_in_the_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    assert runtime_file.runtime_path() == tmp_path / "cache" / "armfleet" / "world.json"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path / "missing"))
    assert runtime_file.runtime_path() == tmp_path / "cache" / "armfleet" / "world.json"
