"""A world run by ``armfleet spawn`` in a subprocess, and CLI clients, for the live-API tests.

Every world gets its own runtime folder (``XDG_RUNTIME_DIR``), so tests never
see a world the user is running, nor each other's.
"""

from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import armfleet

ARMFLEET = [sys.executable, "-m", "armfleet.cli.main"]
#: Longest wait for a world to start or stop [s] (a generous bound, not a timing test).
START_TIMEOUT_S = 60.0


def runtime_env(runtime_dir: Path) -> dict[str, str]:
    return os.environ | {"XDG_RUNTIME_DIR": str(runtime_dir), "PYTHONUNBUFFERED": "1"}


class WorldProcess:
    """``armfleet spawn ARGS...`` running until :meth:`stop`.

    Attributes:
        address: the API address it printed.
        stdout, stderr: lines printed so far.
    """

    def __init__(self, runtime_dir: Path, *args: str) -> None:
        self.runtime_dir = runtime_dir
        self.process = subprocess.Popen(
            [*ARMFLEET, "spawn", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=runtime_env(runtime_dir),
        )
        self.stdout: list[str] = []
        self.stderr: list[str] = []
        self._lines: queue.Queue[str] = queue.Queue()
        self._readers = [
            threading.Thread(target=self._read, args=(self.process.stdout, self.stdout, True)),
            threading.Thread(target=self._read, args=(self.process.stderr, self.stderr, False)),
        ]
        for reader in self._readers:
            reader.start()
        self.address = ""
        try:
            self.address = self.wait_for_line("api: ").split("api: ", 1)[1].strip()
        except BaseException:
            self.stop()
            raise

    def _read(self, stream: object, lines: list[str], forward: bool) -> None:
        for line in stream:  # type: ignore[attr-defined]
            lines.append(line.rstrip("\n"))
            if forward:
                self._lines.put(line.rstrip("\n"))

    def wait_for_line(self, start: str, timeout: float = START_TIMEOUT_S) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self._lines.get(timeout=0.1)
            except queue.Empty:
                if self.process.poll() is not None:
                    raise AssertionError(
                        f"world exited ({self.process.returncode}): {self.stderr}"
                    ) from None
                continue
            if line.startswith(start):
                return line
        raise AssertionError(f"no line starting with {start!r} in {timeout} s: {self.stdout}")

    @property
    def pid(self) -> int:
        return self.process.pid

    def stop(self) -> int:
        """SIGTERM (a clean shutdown), then SIGKILL if it hangs; return the exit code."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=START_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for reader in self._readers:
            reader.join(timeout=5)
        return self.process.returncode

    def __enter__(self) -> WorldProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def cli(runtime_dir: Path, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    """Run ``armfleet ARGS...`` as a client would, in the given runtime folder."""
    return subprocess.run(
        [*ARMFLEET, *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=runtime_env(runtime_dir),
    )


def runtime_file(runtime_dir: Path) -> Path:
    return runtime_dir / "armfleet" / "world.json"


def registered_pid(runtime_dir: Path) -> int:
    return int(json.loads(runtime_file(runtime_dir).read_text())["pid"])


def wait_until(condition: object, timeout: float = 10.0, period: float = 0.02) -> bool:
    """Poll ``condition()`` until true or ``timeout`` [s]; return its last value."""
    deadline = time.monotonic() + timeout
    while True:
        if condition():  # type: ignore[operator]
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(period)


def world_times(client: armfleet.remote.Client, count: int, period: float) -> list[float]:
    """``count`` samples of the world's simulated time, ``period`` [s] of wall time apart."""
    samples = []
    for _ in range(count):
        samples.append(client.info().time_s)
        time.sleep(period)
    return samples


def api_threads() -> list[threading.Thread]:
    """Threads of the live API still running in this process (none after a clean test)."""
    return [t for t in threading.enumerate() if t.name in ("armfleet-api", "armfleet-stream")]
