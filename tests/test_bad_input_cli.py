"""Bad input on the command line (issue #14): every mistake is one line on stderr, exit
code 2, no traceback, and the world it was aimed at is untouched.

The commands run as real subprocesses against a world running in another process
(bob, a Panda at home, fingers at 0.04 m), in a private runtime folder. "Untouched"
means, once every bad command has ended: the world still steps, has the same arms and
no objects, bob holds within 2e-3 rad of home (a move a bad command let through goes
to a target 0.5 rad away and is over long before the check) and his fingers are within
0.5 mm of 0.04 m (a close that got through leaves them shut). Also here: a port in use
is refused before a new world starts, and the world refuses the same ranges from a
client that skips the command line.

The command line's other words (--help's ranges, the status line, a joining spawn's
first line) are in test_cli_help_and_status.py, away from this file's running world.
"""

from __future__ import annotations

import re
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import cast

import numpy as np
import pytest

import armfleet
from armfleet.errors import InvalidNumber
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env, wait_until

HOME = "0,-0.785,0,-2.356,0,1.571,0.785"
PANDA_HOME = [float(v) for v in HOME.split(",")]
#: A target 0.5 rad from home on joint 1: a move that got through ends far from home.
AWAY = ["0.5", *HOME.split(",")[1:]]
#: A settled arm stays this close to its target [rad] (the CLI tests' holding figure).
HOLD_TOLERANCE_RAD = 2e-3
#: Fingers at rest stay this close to their width [m].
WIDTH_TOLERANCE_M = 5e-4
START_WIDTH_M = 0.04
#: Commands started at once (each only parses, or fails at its first request).
BATCH = 6
#: A bad command still running after this long hangs [s] (a generous bound, not a timing).
HANG_S = 120

#: Bob's tool 3 cm into the floor, joint limits kept: a goal in collision.
IN_THE_FLOOR = ["0", "1.7", "0", "-0.8", "0", "3.5", "0.785"]
WAIT_RANGE = "give seconds in [0, 600]"
CLEARANCE_RANGE = "give metres in [0.001, 0.5]"
PLANNING_RANGE = "give seconds in [0.001, 60]"
TIMEOUT_RANGE = "give seconds in [0.001, 600]"
STEP_RANGE = "give steps, an integer in 1..100000"
#: A folder that exists wherever the tests run.
TESTS_DIR = Path(__file__).parent
#: An error line stays readable: a value echoed back is cut short [characters].
LONGEST_LINE = 1000


BAD = [
    # -- numbers at the edges: refused while parsing, before anything is sent ------------
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--wait", "--wait-timeout", "nan"],
        ["argument --wait-timeout: 'nan' is invalid", WAIT_RANGE],
        id="move --wait-timeout nan -> refused before the arm moves",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--wait", "--wait-timeout", "1e308"],
        ["argument --wait-timeout: '1e308' is invalid", WAIT_RANGE],
        id="move --wait-timeout 1e308 -> refused before the arm moves",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--wait", "--wait-timeout", "-1"],
        ["argument --wait-timeout: '-1' is invalid", WAIT_RANGE],
        id="move --wait-timeout -1 -> refused before the arm moves (not after)",
    ),
    pytest.param(
        ["move-together", f"bob={','.join(AWAY)}", "--wait", "--wait-timeout", "-inf"],
        ["argument --wait-timeout: '-inf' is invalid", WAIT_RANGE],
        id="move-together --wait-timeout -inf -> refused before the arm moves",
    ),
    pytest.param(
        ["grip", "bob", "close", "--wait", "--wait-timeout", "inf"],
        ["argument --wait-timeout: 'inf' is invalid", WAIT_RANGE],
        id="grip --wait-timeout inf -> refused before the fingers close",
    ),
    pytest.param(
        ["info", "--timeout", "1e308"],
        ["argument --timeout: '1e308' is invalid", TIMEOUT_RANGE],
        id="--timeout 1e308 -> one line, not an OverflowError",
    ),
    pytest.param(
        ["arms", "--timeout", "-0"],
        ["argument --timeout: '-0' is invalid", TIMEOUT_RANGE],
        id="--timeout -0 -> refused",
    ),
    pytest.param(
        ["info", "--timeout", "soon"],
        ["argument --timeout: 'soon' is not a number", TIMEOUT_RANGE],
        id="--timeout text -> not a number, with the range",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,1.5", "--timeout", "1e308"],
        ["argument --timeout: '1e308' is invalid", TIMEOUT_RANGE],
        id="spawn into the running world with --timeout 1e308 -> no arm added",
    ),
    pytest.param(
        ["step", "1000000000000"],
        ["argument N: '1000000000000' is invalid", STEP_RANGE],
        id="step 1e12 -> refused, not an OverflowError",
    ),
    pytest.param(
        ["step", "2.5"],
        ["argument N: '2.5' is not an integer", STEP_RANGE],
        id="step 2.5 -> not an integer",
    ),
    pytest.param(["step", "0"], ["argument N: '0' is invalid", STEP_RANGE], id="step 0 -> refused"),
    pytest.param(
        ["spawn", "carl", "--at", "0,0", "--new-world", "--duration", "1e308"],
        ["argument --duration: '1e308' is invalid", "give seconds in [0, 1000000]"],
        id="--duration 1e308 -> refused (would never end)",
    ),
    pytest.param(
        ["launch", "bob_and_toby", "--check", "--duration", "nan"],
        ["argument --duration: 'nan' is invalid", "give seconds in [0, 1000000]"],
        id="launch --check --duration nan -> refused",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,0", "--new-world", "--api-port", "99999999999999999999"],
        ["argument --api-port: '99999999999999999999' is invalid", "integer in 0..65535"],
        id="--api-port huge int -> refused",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,0", "--new-world", "--viewer-port", "0"],
        ["argument --viewer-port: '0' is invalid", "integer in 1..65535"],
        id="--viewer-port 0 -> refused",
    ),
    pytest.param(
        ["replay", "run.mcap", "--speed", "inf"],
        ["argument --speed: 'inf' is invalid", "in [0.001, 1000]"],
        id="replay --speed inf -> refused before the file is read",
    ),
    # -- positions and angles: a world coordinate is within 1000 m, an angle within 360 deg --
    pytest.param(
        ["spawn", "carl", "--at", "1e308,1.5"],
        ["spawn pose x is 1e+308; give metres in [-1000, 1000]"],
        id="spawn --at 1e308 -> refused (such an arm slowed the shared world 5x)",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,1.5,0,720"],
        ["spawn pose yaw is 720; give degrees in [-360, 360]"],
        id="spawn yaw 720 -> refused",
    ),
    pytest.param(
        ["add-object", "cup", "sphere", "--size", "0.03", "--at", "1e308", "0", "0"],
        ["object 'cup': at: [1e+308, 0.0, 0.0] is out of range", "metres in [-1000, 1000]"],
        id="add-object --at 1e308 -> refused by the world, nothing added",
    ),
    pytest.param(
        [
            "add-object",
            "cup",
            "sphere",
            "--size",
            "0.03",
            "--at",
            "0.5",
            "0.5",
            "0.03",
            "--yaw",
            "-1e308",
        ],
        ["object 'cup': rpy_deg: [0.0, 0.0, -1e+308] is out of range", "[-360, 360]"],
        id="add-object --yaw -1e308 -> refused by the world, nothing added",
    ),
    pytest.param(
        ["move", "bob", "--pose", "1e308", "0", "0.4"],
        ["a pose's position [1e+308, 0.0, 0.4] is out of range", "metres in [-1000, 1000]"],
        id="move --pose x 1e308 -> refused by the world, nothing moved",
    ),
    pytest.param(
        ["move", "bob", "--pose", "0.4", "0", "0.4", "1e308", "0", "0"],
        ["--pose roll = 1e+308 is invalid; give degrees in [-360, 360]"],
        id="move --pose roll 1e308 -> refused before sending",
    ),
    # -- names and lists --------------------------------------------------------------------
    pytest.param(
        ["spwan", "carl", "--at", "0,1.5"],
        ["invalid choice: 'spwan'; did you mean 'spawn'?", "'move-together'"],
        id="misspelt command -> did you mean, and the commands",
    ),
    pytest.param(
        ["add-object", "cup", "sphre", "--size", "0.03"],
        ["invalid choice: 'sphre'; did you mean 'sphere'?", "'box', 'cylinder', 'sphere'"],
        id="misspelt shape -> did you mean, and the shapes",
    ),
    pytest.param(
        ["spawn", "--at", "0,1.5", "carl"],
        ["--at took 'carl' as a position", "'armfleet spawn carl --at 0,1.5'"],
        id="names after --at -> --at took them, put them first",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,1.5", "dave"],
        ["--at took 'dave' as a position", "'armfleet spawn carl dave --at 0,1.5'"],
        id="one name after --at -> --at took it, not a count mismatch",
    ),
    pytest.param(
        ["spawn", "carl", "dave", "--at", "0,1.5"],
        ["got 2 names but 1 --at poses"],
        id="fewer --at poses than names -> counts named",
    ),
    pytest.param(
        ["move", "", "--joints", *AWAY], ["no arm named ''; arms: bob"], id="empty arm name"
    ),
    pytest.param(
        ["info", "--connect", ""], ["address '' is malformed"], id="empty --connect address"
    ),
    # -- positional arguments taken by an option of several values (one rule for all) ----
    pytest.param(
        ["spawn", "--model", "ur5", "carl", "--at", "0,1.5"],
        ["--model took 'carl' as a model", "'armfleet spawn carl --model ur5 --at 0,1.5'"],
        id="name after --model -> --model took it, put names first (not 'required: NAME')",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,1.5", "--model", "ur5", "dave"],
        ["--model took 'dave' as a model", "'armfleet spawn carl dave --at 0,1.5 --model ur5'"],
        id="one name after --model -> --model took it, not a count mismatch",
    ),
    pytest.param(
        ["move", "--joints", *AWAY, "bob"],
        ["--joints took 'bob' as a value", f"'armfleet move bob --joints {' '.join(AWAY)}'"],
        id="name after --joints -> --joints took it (not 'invalid float'), nothing moves",
    ),
    pytest.param(
        ["plot", "--arm", "bob", "run.mcap"],
        ["--arm took 'run.mcap' as an arm name", "'armfleet plot run.mcap --arm bob'"],
        id="recording after plot --arm -> --arm took it, put it first",
    ),
    # -- unknown options: checked first, with the command's own options -------------------
    pytest.param(
        ["spawn", "carl", "--wiat"],
        ["unknown option '--wiat'", "(options: --help, --at, --model,"],
        id="unknown spawn option -> named with spawn's options (not 'required: --at')",
    ),
    pytest.param(
        ["move", "bob", "--wait-timout", "3"],
        ["unknown option '--wait-timout'; did you mean '--wait-timeout'?"],
        id="misspelt move option -> did you mean, from move's own options",
    ),
    # -- paths: a folder, an empty path -----------------------------------------------------
    pytest.param(
        ["launch", str(TESTS_DIR)],
        [f"{TESTS_DIR}: is a folder, not a regular file; give a spec file (.yaml) or a shipped"],
        id="launch a folder -> it is a folder, give a spec file or a shipped name",
    ),
    pytest.param(
        ["plot", ""],
        ["argument RUN.mcap: the path is empty"],
        id="plot '' -> the path is empty (not '.')",
    ),
    pytest.param(
        ["replay", ""], ["argument RUN.mcap: the path is empty"], id="replay '' -> path is empty"
    ),
    pytest.param(
        ["info", ""], ["argument RUN.mcap: the path is empty"], id="info '' -> path is empty"
    ),
    pytest.param(
        ["recover", ""],
        ["argument RUN.mcap: the path is empty"],
        id="recover '' -> path is empty (not a traceback)",
    ),
    pytest.param(
        ["recover", "run.mcap", "-o", " "],
        ["argument -o/--output: the path is blank (' ')"],
        id="recover -o blank -> path is blank",
    ),
    pytest.param(
        ["launch", ""], ["argument SPEC: the path is empty"], id="launch '' -> path is empty"
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,1.5", "--new-world", "--duration", "0", "--record", ""],
        ["argument --record: the path is empty"],
        id="spawn --record '' -> path is empty",
    ),
    # -- audit: repeated options, arguments left over, 100 kB values ---------------------------
    pytest.param(
        ["move", "bob", "carl", "--joints", *AWAY],
        ["'armfleet move' does not take the argument 'carl' (see 'armfleet move --help')"],
        id="an argument too many -> named with its command's help (not 'armfleet --help')",
    ),
    pytest.param(
        ["spawn", "carl", "--at", "0,1.5", "--at", "1,1.5"],
        ["--at is given twice; give it once (all its values after one)"],
        id="--at given twice -> refused (the last won: carl came up at the second pose)",
    ),
    pytest.param(
        ["launch", "a" * 100_000],
        ["cannot be opened (File name too long)"],
        id="launch with a 100 kB name -> one short line (not an OSError traceback)",
    ),
    pytest.param(
        ["info", "--connect", "b" * 100_000],
        [f"address '{'b' * 95}...(100002 characters) is malformed"],
        id="--connect 100 kB -> one short line (the value was echoed whole)",
    ),
    # -- collision-free moves (issue 16): the planner's ranges, checked while parsing ------
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--avoid-collisions", "--clearance", "0"],
        ["argument --clearance: '0' is invalid", CLEARANCE_RANGE],
        id="move --avoid-collisions --clearance 0 -> refused before anything is sent",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--avoid-collisions", "--clearance", "nan"],
        ["argument --clearance: 'nan' is invalid", CLEARANCE_RANGE],
        id="move --avoid-collisions --clearance nan -> refused before anything is sent",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--avoid-collisions", "--planning-timeout", "-1"],
        ["argument --planning-timeout: '-1' is invalid", PLANNING_RANGE],
        id="move --avoid-collisions --planning-timeout -1 -> refused before anything is sent",
    ),
    pytest.param(
        [
            "move-together",
            f"bob={','.join(AWAY)}",
            "--avoid-collisions",
            "--planning-timeout",
            "1e308",
        ],
        ["argument --planning-timeout: '1e308' is invalid", PLANNING_RANGE],
        id="move-together --avoid-collisions --planning-timeout 1e308 -> refused",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--avoid-collisions", "--budget", "0"],
        ["argument --budget: '0' is invalid", "planner iterations, an integer in 1..1000000"],
        id="move --avoid-collisions --budget 0 -> refused before anything is sent",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--avoid-collisions", "--budget", "2.5"],
        ["argument --budget: '2.5' is not an integer"],
        id="move --avoid-collisions --budget 2.5 -> refused before anything is sent",
    ),
    pytest.param(
        [
            "move",
            "bob",
            "--joints",
            *AWAY,
            "--avoid-collisions",
            "--budget",
            "9",
            "--planning-timeout",
            "1",
        ],
        ["--planning-timeout (wall time) and --budget (planner iterations) exclude each other"],
        id="move --budget with --planning-timeout -> one or the other, nothing sent",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--budget", "100"],
        ["--budget goes with --avoid-collisions"],
        id="move --budget without --avoid-collisions -> refused, nothing sent",
    ),
    pytest.param(
        ["move", "bob", "--pose", "0.4", "0", "0.5", "--linear", "--avoid-collisions"],
        ["argument --avoid-collisions: not allowed with argument --linear"],
        id="move --pose --linear --avoid-collisions -> one or the other, nothing sent",
    ),
    pytest.param(
        ["move", "bob", "--joints", *AWAY, "--clearance", "0.02"],
        ["--clearance goes with --avoid-collisions"],
        id="move --clearance without --avoid-collisions -> refused (not a straight move)",
    ),
    pytest.param(
        ["move-together", f"bob={','.join(AWAY)}", "--planning-timeout", "2"],
        ["--planning-timeout goes with --avoid-collisions"],
        id="move-together --planning-timeout without --avoid-collisions -> refused",
    ),
    pytest.param(
        ["move", "bob", "--joints", *IN_THE_FLOOR, "--avoid-collisions", "--wait"],
        ["cannot plan bob: goal in collision: bob_panda_", " touches ground (clearance 10 mm"],
        id="move --avoid-collisions to a goal in the floor -> the world's one line, no motion",
    ),
]


def run_all(runtime: Path, invocations: list[list[str]]) -> list[subprocess.CompletedProcess[str]]:
    """Run the commands, a few at a time (two cores are shared)."""
    results: list[subprocess.CompletedProcess[str]] = []
    for start in range(0, len(invocations), BATCH):
        processes = [
            subprocess.Popen(
                [*ARMFLEET, *args],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env=runtime_env(runtime),
            )
            for args in invocations[start : start + BATCH]
        ]
        for process in processes:
            try:
                stdout, stderr = process.communicate(timeout=HANG_S)
            except subprocess.TimeoutExpired:  # e.g. a --duration that never ends
                process.kill()
                stdout, stderr = process.communicate()
                stderr += f"(still running after {HANG_S} s: killed)"
            results.append(
                subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)
            )
    return results


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    """bob, a Panda, in a world running in real time in another process."""
    with WorldProcess(
        tmp_path_factory.mktemp("runtime"), "bob", "--at", "0,0", "--no-viewer", "--realtime"
    ) as process:
        yield process


@pytest.fixture(scope="module")
def bad_runs(world: WorldProcess) -> dict[str, subprocess.CompletedProcess[str]]:
    """Every bad invocation, once bob holds home with his fingers at 0.04 m."""
    home = cli(world.runtime_dir, "move", "bob", "--joints", *HOME.split(","), "--wait")
    assert home.returncode == 0, home.stderr
    with armfleet.connect(world.address) as client:
        assert abs(client.arm("bob").gripper.width - START_WIDTH_M) < WIDTH_TOLERANCE_M
    invocations = [cast(list[str], param.values[0]) for param in BAD]
    results = run_all(world.runtime_dir, invocations)
    return {str(param.id): result for param, result in zip(BAD, results, strict=True)}


@pytest.mark.parametrize(("args", "fragments"), BAD)
def test_a_bad_command_is_one_line_and_exit_2(
    bad_runs: dict[str, subprocess.CompletedProcess[str]],
    request: pytest.FixtureRequest,
    args: list[str],
    fragments: list[str],
) -> None:
    result = bad_runs[request.node.callspec.id]
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout == ""  # nothing was done, nothing to report
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr[:LONGEST_LINE]
    assert len(lines[0]) <= LONGEST_LINE, lines[0][:LONGEST_LINE]
    assert lines[0].startswith("armfleet: error: ")
    for fragment in fragments:
        assert fragment in lines[0]


def test_after_the_bad_commands_the_world_is_untouched(
    bad_runs: dict[str, subprocess.CompletedProcess[str]], world: WorldProcess
) -> None:
    with armfleet.connect(world.address) as client:
        start = client.info().time_s
        assert wait_until(lambda: client.info().time_s > start + 0.01)  # still stepping
        assert list(client.arms) == ["bob"]
        assert client.objects == {}
        bob = client.arm("bob")
        assert bob.mode is armfleet.ArmMode.HOLDING
        assert np.abs(bob.positions - PANDA_HOME).max() < HOLD_TOLERANCE_RAD
        assert abs(bob.gripper.width - START_WIDTH_M) < WIDTH_TOLERANCE_M
        assert client.info().streams == 0


PORT_TAKEN = "(Address already in use)"


@pytest.mark.parametrize(
    "option",
    [
        pytest.param(
            "--api-port",
            id="--api-port taken -> refused before any arm comes up (it failed after bring-up)",
        ),
        pytest.param(
            "--viewer-port",
            id="--viewer-port taken -> refused (the run went on without its viewer, exit 0)",
        ),
    ],
)
def test_a_port_in_use_is_refused_before_the_world_starts(world: WorldProcess, option: str) -> None:
    """The running world's API port is taken for sure; a new world asked to listen there
    stops at once, in one line, with nothing on stdout (no bring-up, no viewer URL)."""
    port = world.address.rsplit(":", 1)[1]
    result = cli(
        world.runtime_dir, "spawn", "carl", "--at", "0,0", "--new-world", "--duration", "0",
        option, port,
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    assert result.stdout == ""
    assert result.stderr.splitlines() == [
        f"armfleet: error: {option} {port}: cannot listen on 127.0.0.1:{port} {PORT_TAKEN}; "
        + ("choose another, or 0 for a free one" if option == "--api-port" else "choose "
           "another, or leave it out")
    ]  # fmt: skip


# -- the same ranges in the live API and the Python client ------------------------------------


def test_the_world_refuses_what_the_command_line_refuses(world: WorldProcess) -> None:
    """A client that skips the CLI (a raw request) meets the same ranges at the server."""
    with armfleet.connect(world.address) as client:
        for op, args, expected in (
            ("wait", {"name": "bob", "timeout_s": float("nan")}, WAIT_RANGE),
            ("wait", {"name": "bob", "timeout_s": 1e308}, WAIT_RANGE),
            ("step", {"count": 10**12}, STEP_RANGE),
            ("step", {"count": 2.5}, STEP_RANGE),
            ("move", {"name": "bob", "positions": PANDA_HOME, "avoid_collisions": True,
                      "clearance_m": 0.0}, CLEARANCE_RANGE),
            ("move_together", {"targets": {"bob": PANDA_HOME}, "avoid_collisions": True,
                               "timeout_s": -1.0}, PLANNING_RANGE),
        ):  # fmt: skip
            with pytest.raises(armfleet.ArmfleetError, match=re.escape(expected)):
                client.call(op, args)
        bob = client.arm("bob")
        for bad in (float("nan"), 1e308, -1.0):
            with pytest.raises(InvalidNumber, match=re.escape("bob: wait timeout")):
                bob.wait(bad)
            with pytest.raises(InvalidNumber, match=re.escape("bob: gripper wait timeout")):
                bob.gripper.wait(bad)
        with pytest.raises(InvalidNumber, match=re.escape("step count = 1000000000000")):
            client.step(10**12)
    with pytest.raises(InvalidNumber, match=re.escape("timeout = 1e+308 is invalid")):
        armfleet.connect(world.address, timeout=1e308)
