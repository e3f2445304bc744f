"""The command line's words beside its errors (issue #14, items 5, 17, 18): --help shows
each numeric option's valid range; the Python API refuses an empty path as the command
line does; a spawn that joins a running world says which world first; the status line
sums up arms beyond the terminal's width, and a --duration run ends with a closing line.

Split from test_bad_input_cli.py, whose bad commands need a world running for them:
these tests need none (or start their own).
"""

from __future__ import annotations

import re
import subprocess
import time
from collections import Counter
from collections.abc import Callable, Iterator
from datetime import datetime
from pathlib import Path

import pytest

import armfleet
from armfleet.checks.user_paths import EmptyPath
from armfleet.cli.status_line import status_line
from armfleet.messages import ArmMode
from armfleet.recording import export_html, open_recording, plot_recording, recover
from armfleet.spec import load_spec
from tests.conftest import RecordedRun
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env

# -- item 5: --help shows each numeric option's valid range ------------------------------------

SECONDS_WAIT = "seconds in [0, 600]"
SECONDS_ANSWER = "seconds in [0.001, 600]"
SECONDS_RUN = "seconds in [0, 1000000]"
USER_PORT = "a TCP port, an integer in 1..65535"
API_PORT = "a TCP port (0: a free one), an integer in 0..65535"

METRES = "metres in [-1000, 1000]"
CLEARANCE_METRES = "metres in [0.001, 0.5]"
SECONDS_PLAN = "seconds in [0.001, 60]"
DEGREES = "degrees in [-360, 360]"

HELP_RANGES = {
    "spawn": {"--duration S": SECONDS_RUN, "--viewer-port PORT": USER_PORT,
              "--api-port PORT": API_PORT, "--timeout S": SECONDS_ANSWER,
              "--at X,Y[,Z[,YAW_DEG]] [X,Y[,Z[,YAW_DEG]] ...]":
                  f"X Y Z {METRES}, YAW_DEG {DEGREES}"},
    "launch": {"--duration S": SECONDS_RUN, "--viewer-port PORT": USER_PORT,
               "--api-port PORT": API_PORT},
    "move": {"--wait-timeout S": SECONDS_WAIT, "--timeout S": SECONDS_ANSWER,
             "--pose V [V ...]": f"X Y Z {METRES}, angles {DEGREES}",
             "--clearance M": CLEARANCE_METRES, "--planning-timeout S": SECONDS_PLAN},
    "move-together": {"--wait-timeout S": SECONDS_WAIT, "--timeout S": SECONDS_ANSWER,
                      "--clearance M": CLEARANCE_METRES, "--planning-timeout S": SECONDS_PLAN},
    "grip": {"--wait-timeout S": SECONDS_WAIT, "--timeout S": SECONDS_ANSWER},
    "step": {"N": "steps, an integer in 1..100000", "--timeout S": SECONDS_ANSWER},
    "arms": {"--timeout S": SECONDS_ANSWER},
    "info": {"--timeout S": SECONDS_ANSWER},
    "replay": {"--speed X": "a factor (times real time) in [0.001, 1000]",
               "--viewer-port PORT": USER_PORT},
    "add-object": {"--size M [M ...]": "metres, each in (0, 100]",
                   "--mass KG": "kg in [0, 10000]", "--at X Y Z": METRES,
                   "--yaw DEG": DEGREES, "--timeout S": SECONDS_ANSWER},
}  # fmt: skip


def help_entries(text: str) -> dict[str, str]:
    """Each argument's entry of a --help text, by its first line's start, on one line."""
    entries: dict[str, list[str]] = {}
    current: list[str] = []
    for line in text.splitlines():
        if re.match(r"^  \S", line):
            current = [line.strip()]
            head = re.split(r"\s{2,}", line.strip())[0]
            entries[head] = current
        elif line.startswith("   ") and current:
            current.append(line.strip())
        else:
            current = []
    return {head: " ".join(" ".join(lines).split()) for head, lines in entries.items()}


@pytest.mark.parametrize("command", list(HELP_RANGES))
def test_help_shows_the_range_of_each_numeric_option(command: str) -> None:
    result = subprocess.run(
        [*ARMFLEET, command, "--help"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    entries = help_entries(result.stdout)
    for head, valid in HELP_RANGES[command].items():
        assert head in entries, (head, list(entries))
        assert entries[head].endswith(f"; valid: {valid}"), entries[head]


# -- the Python API refuses an empty path, as the command line does -------------------------


def _record_to_empty_path(run: RecordedRun) -> None:
    with armfleet.World() as world:
        armfleet.Recorder(world, "")


@pytest.mark.parametrize(
    ("call", "expected"),
    [
        pytest.param(
            lambda run: open_recording(""),
            "recording: the path is empty; give a file path",
            id="open_recording('') -> EmptyPath (not '. is not an MCAP recording')",
        ),
        pytest.param(
            lambda run: recover(""),
            "recording: the path is empty",
            id="recover('') -> EmptyPath (not ValueError: '.' has an empty name)",
        ),
        pytest.param(
            lambda run: recover(run.path, " "),
            "output: the path is blank (' ')",
            id="recover(output=' ') -> EmptyPath",
        ),
        pytest.param(
            lambda run: load_spec(""),
            "launch spec: the path is empty",
            id="load_spec('') -> EmptyPath",
        ),
        pytest.param(
            lambda run: plot_recording(open_recording(run.path), output=""),
            "output: the path is empty",
            id="plot_recording(output='') -> EmptyPath (wrote the figures into the current folder)",
        ),
        pytest.param(
            lambda run: export_html(open_recording(run.path), ""),
            "HTML replay: the path is empty",
            id="export_html('') -> EmptyPath",
        ),
        pytest.param(
            _record_to_empty_path, "recording: the path is empty", id="Recorder('') -> EmptyPath"
        ),
    ],
)
def test_the_python_api_refuses_an_empty_path_as_the_command_line_does(
    recorded_run: RecordedRun,
    call: Callable[[RecordedRun], object],
    expected: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """One rule (armfleet.checks.user_paths) for every path given as text; nothing is written."""
    monkeypatch.chdir(tmp_path)  # whatever is written to '.' would land here
    with pytest.raises(EmptyPath, match=re.escape(expected)):
        call(recorded_run)
    assert list(tmp_path.iterdir()) == []


# -- item 18: a spawn that joins says which world ----------------------------------------------

JOIN_LINE = re.compile(
    r"^joining the running world at (?P<address>\S+) \(process (?P<pid>\d+), started "
    r"(?P<started>\d{4}-\d\d-\d\d \d\d:\d\d:\d\d), [0-9.]+ (s|min|h|days) ago; "
    r"arms: (?P<arms>[a-z0-9_, ]+)\); add --new-world for a separate world$"
)


def test_a_spawn_that_joins_says_which_world_first(tmp_path: Path) -> None:
    before = time.time()
    with WorldProcess(tmp_path, "bob", "--at", "0,0", "--no-viewer", "--fast") as world:
        after = time.time()
        result = cli(tmp_path, "spawn", "carl", "--at", "0,1.5")
        assert result.returncode == 0, result.stderr
        first = result.stdout.splitlines()[0]
        match = JOIN_LINE.match(first)
        assert match, first
        assert match["address"] == world.address
        assert int(match["pid"]) == world.pid
        assert match["arms"] == "bob"  # the world as it was: carl not yet there
        started = datetime.strptime(match["started"], "%Y-%m-%d %H:%M:%S").timestamp()
        # Printed to the second, in local time: between our launch and its "api:" line.
        assert before - 1 <= started <= after + 1
        with armfleet.connect(world.address) as client:
            assert list(client.arms) == ["bob", "carl"]
        # A new world says nothing of the sort.
        separate = cli(tmp_path, "spawn", "dave", "--at", "0,0", "--new-world", "--duration", "0")
        assert separate.returncode == 0, separate.stderr
        assert "joining" not in separate.stdout


# -- item 17: status summary beyond the terminal's width, closing line --------------------------


@pytest.fixture(scope="module")
def fleet() -> Iterator[armfleet.World]:
    """30 Pandas on a 1 m grid: 2 stopped, 1 moving, the rest holding."""
    with armfleet.World() as world:
        arms = [world.spawn(f"arm{i:02d}", at=(i % 6, i // 6)) for i in range(30)]
        arms[4].position_controller.protective_stop("touched ground")
        arms[17].position_controller.protective_stop("touched arm16")
        target = arms[9].positions.copy()
        target[0] += 0.5
        arms[9].move_to(target)
        world.run(0.05)
        yield world


def test_thirty_arms_are_summarised_within_the_width(fleet: armfleet.World) -> None:
    modes = Counter(arm.status(fleet.time).mode for arm in fleet.arms.values())
    assert modes == {ArmMode.HOLDING: 27, ArmMode.MOVING: 1, ArmMode.PROTECTIVE_STOP: 2}
    full = status_line(fleet, 1.0, width=100_000)
    assert len(full) > 1500  # the 1,900-character line
    line = status_line(fleet, 1.0, width=150)
    assert len(line) <= 150, line
    head, counts, attention = line.split(" | ")
    assert head == full.split(" | ")[0]
    assert counts == "30 arms: 27 holding, 1 moving, 2 protective stop"
    assert attention == "attention: arm04 STOP(touched ground), arm17 STOP(touched arm16)"


@pytest.mark.parametrize("width", [130, 100])
def test_arms_needing_attention_beyond_the_width_are_counted(
    fleet: armfleet.World, width: int
) -> None:
    line = status_line(fleet, 1.0, width=width)
    assert len(line) <= width, line
    assert " | 30 arms: 27 holding, 1 moving, 2 protective stop | attention: " in line
    attention = line.split(" | attention: ")[1]
    shown = re.findall(r"arm\d\d STOP\([^)]*\)", attention)
    hidden = re.fullmatch(r"(.*, )?\+(?P<n>\d+) more|(?P<all>\d+) arms", attention)
    assert hidden, attention
    # Every stopped arm is named or counted, never both.
    assert len(shown) + int(hidden["n"] or hidden["all"]) == 2


def test_a_duration_run_summarises_in_a_pipe_and_ends_with_a_closing_line(
    tmp_path: Path,
) -> None:
    """Output to a pipe is taken as 100 columns; four arms' full line is wider."""
    env = {key: value for key, value in runtime_env(tmp_path).items() if key != "COLUMNS"}
    names = ["a", "b", "c", "d"]
    result = subprocess.run(
        [*ARMFLEET, "spawn", *names, "--at", "0,0", "1,0", "2,0", "3,0", "--no-viewer",
         "--realtime", "--duration", "1.2"],
        capture_output=True, text=True, timeout=120, env=env,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    status = [line for line in lines if line.startswith("t=")]
    assert status, result.stdout  # 1.2 s in real time: at least one status line
    for line in status:
        assert len(line) <= 100, line
        assert line.endswith(" | 4 arms: 4 holding"), line
    closing = re.match(
        r"^ran --duration 1\.2 s \(t=(?P<t>[0-9.]+)s, [0-9.]+ s wall in all\); shut down "
        r"cleanly$",
        lines[-1],
    )
    assert closing, lines[-1]
    assert float(closing["t"]) >= 1.2


def test_status_lines_that_fit_stay_per_arm(tmp_path: Path) -> None:
    result = subprocess.run(
        [*ARMFLEET, "spawn", "a", "--at", "0,0", "--no-viewer", "--realtime", "--duration", "1.2"],
        capture_output=True, text=True, timeout=120,
        env=runtime_env(tmp_path) | {"COLUMNS": "200"},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    status = [line for line in result.stdout.splitlines() if line.startswith("t=")]
    assert status, result.stdout
    assert all(re.search(r" \| a holding q=\[[-+0-9. ]+\]$", line) for line in status), status
