"""Every command docs/planning.md shows runs as shown, in the world the page sets up, and
prints what the page says it prints (issue 28, item 20: its examples were refused in the
shared cell, and the error it showed came from neither world).

The page's ``console`` blocks are the script: ``$ armfleet launch ...`` starts the world (as
a subprocess, in a runtime folder of its own), every other ``$ armfleet ...`` line runs
against it as a CLI subprocess, in the page's order, and the lines after a command are its
output. Numbers are compared as numbers of any value (a planned path's times and an arm's
last digits vary); everything else word for word, and the exit code is 2 exactly when the
page shows an error.
"""

from __future__ import annotations

import queue
import re
import shlex
import signal
import subprocess
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from tests.remote_world import ARMFLEET, START_TIMEOUT_S, cli, runtime_env

PAGE = Path(__file__).resolve().parents[1] / "docs" / "planning.md"
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?")


@dataclass
class Command:
    """One ``$ armfleet ...`` line of the page and the output shown under it."""

    line: str
    output: list[str] = field(default_factory=list)

    @property
    def args(self) -> list[str]:
        words = shlex.split(self.line)
        assert words[0] == "armfleet", self.line
        return words[1:]


def console_commands(text: str) -> list[Command]:
    """The commands of every ``console`` block, in order, each with its output lines."""
    commands: list[Command] = []
    for block in re.findall(r"^```console\n(.*?)^```", text, re.DOTALL | re.MULTILINE):
        for line in block.splitlines():
            if line.startswith("$ "):
                commands.append(Command(line[2:].strip()))
            elif line.strip():
                assert commands, f"output before any command: {line!r}"
                commands[-1].output.append(line)
    return commands


def shape(line: str) -> re.Pattern[str]:
    """``line`` as a pattern: its numbers any numbers, the rest as written."""
    parts = NUMBER.split(line)
    return re.compile("^" + NUMBER.pattern.join(re.escape(part) for part in parts) + "$")


class LaunchedWorld:
    """``armfleet ARGS...`` (a launch) running until :meth:`stop`; its API line awaited."""

    def __init__(self, runtime_dir: Path, args: list[str]) -> None:
        self.runtime_dir = runtime_dir
        self.process = subprocess.Popen(
            [*ARMFLEET, *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=runtime_env(runtime_dir),
        )
        self.lines: list[str] = []
        self._queue: queue.Queue[str] = queue.Queue()
        self._reader = threading.Thread(target=self._read)
        self._reader.start()
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            try:
                line = self._queue.get(timeout=0.1)
            except queue.Empty:
                if self.process.poll() is not None or time.monotonic() > deadline:
                    self.stop()
                    raise AssertionError(f"the world did not start: {self.lines}") from None
                continue
            if line.startswith("api: "):
                return

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))
            self._queue.put(line.rstrip("\n"))

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=START_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._reader.join(timeout=5)
        return self.process.returncode


@pytest.fixture
def page_commands() -> list[Command]:
    return console_commands(PAGE.read_text())


def test_the_page_launches_the_shared_cell_and_shows_commands(page_commands: list[Command]) -> None:
    """The page's script is what the test runs: a launch of the shared cell first (the
    world of its Python example), then the commands, none outside a ``console`` block."""
    assert page_commands[0].args[:2] == ["launch", "shared_cell"]
    assert 'armfleet.launch("shared_cell"' in PAGE.read_text()
    assert len(page_commands) >= 5
    fenced = re.findall(r"^```(\w*)\n(.*?)^```", PAGE.read_text(), re.DOTALL | re.MULTILINE)
    for language, block in fenced:
        if language != "console":
            assert not re.search(r"^\s*(\$ )?armfleet ", block, re.MULTILINE), block


@pytest.fixture
def shared_cell(tmp_path: Path, page_commands: list[Command]) -> Iterator[LaunchedWorld]:
    world = LaunchedWorld(tmp_path, page_commands[0].args)
    try:
        yield world
    finally:
        world.stop()


def test_every_command_runs_as_shown(
    shared_cell: LaunchedWorld, page_commands: list[Command]
) -> None:
    for command in page_commands[1:]:
        result = cli(shared_cell.runtime_dir, *command.args, timeout=120.0)
        printed = (result.stdout + result.stderr).splitlines()
        shown_error = any(line.startswith("armfleet: error: ") for line in command.output)
        assert result.returncode == (2 if shown_error else 0), (command.line, printed)
        assert "Traceback" not in result.stderr
        assert len(printed) == len(command.output), (command.line, printed, command.output)
        for got, shown in zip(printed, command.output, strict=True):
            assert shape(shown).match(got), f"{command.line}\n  page: {shown}\n  real: {got}"
