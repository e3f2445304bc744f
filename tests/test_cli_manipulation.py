"""``armfleet grip``, ``move --pose``, ``move-together`` and the object commands as a user runs
them: real subprocesses against a world running in another process."""

from __future__ import annotations

import re
import subprocess
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import armfleet
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env, wait_until

HOME = "0,-0.785,0,-2.356,0,1.571,0.785"
PANDA_HOME = [float(v) for v in HOME.split(",")]
WIDTH_TOLERANCE_M = 5e-4
REACHED_M = 1e-3
HOLD_TOLERANCE_RAD = 2e-3
GRIP_LINE = re.compile(
    r"^(?P<arm>\w+): gripper (?P<mode>[a-z ]+), width (?P<width>[0-9.]+) m, "
    r"(?P<holding>holding|not holding) \(t=[0-9.]+s\)$"
)
POSE_LINE = re.compile(
    r"^bob: holding tool0 at \((?P<x>[-0-9.]+), (?P<y>[-0-9.]+), (?P<z>[-0-9.]+)\) m in world, "
    r"(?P<miss>[0-9.]+) mm from the goal, t=[0-9.]+s$"
)


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    """A running world: two Pandas facing each other and a UR3 (no gripper)."""
    with WorldProcess(
        tmp_path_factory.mktemp("runtime"), "bob", "toby", "ur", "--at", "0,0", "1.2,0,0,180",
        "0,1.2", "--model", "panda", "panda", "ur3", "--no-viewer", "--realtime",
    ) as process:  # fmt: skip
        yield process


@pytest.fixture(scope="module")
def runtime(world: WorldProcess) -> Path:
    """Its runtime folder: commands run there find it without --connect."""
    return world.runtime_dir


def ok(runtime: Path, *args: str) -> list[str]:
    """Run ``armfleet ARGS``; it must succeed; its output lines."""
    result = cli(runtime, *args)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    return result.stdout.splitlines()


def test_grip_closes_on_nothing_and_reaches_a_width(world: WorldProcess, runtime: Path) -> None:
    (opened,) = ok(runtime, "grip", "bob", "open", "--wait")
    match = GRIP_LINE.match(opened)
    assert match and match["mode"] == "at width", opened
    assert abs(float(match["width"]) - 0.08) < WIDTH_TOLERANCE_M
    (closed,) = ok(runtime, "grip", "bob", "close", "--force", "30", "--wait")
    match = GRIP_LINE.match(closed)
    assert match and match["mode"] == "closed" and match["holding"] == "not holding", closed
    assert float(match["width"]) < 0.002
    (reached,) = ok(runtime, "grip", "bob", "0.035", "--wait")
    match = GRIP_LINE.match(reached)
    assert match and match["mode"] == "at width", reached
    assert abs(float(match["width"]) - 0.035) < WIDTH_TOLERANCE_M
    with armfleet.connect(world.address) as client:
        assert abs(client.arm("bob").gripper.width - 0.035) < WIDTH_TOLERANCE_M
    arms = ok(runtime, "arms")
    bob = next(line for line in arms if line.startswith("bob "))
    ur = next(line for line in arms if line.startswith("ur "))
    assert "0.035" in bob and " at width " in bob
    assert re.search(r"\s-\s", ur)  # no gripper to show


def test_move_pose_reaches_the_pose_within_1mm(world: WorldProcess, runtime: Path) -> None:
    ok(runtime, "move", "bob", "--joints", *HOME.split(","), "--wait")
    (line,) = ok(
        runtime, "move", "bob", "--pose", "0.45", "-0.1", "0.35", "180", "0", "0", "--wait"
    )
    match = POSE_LINE.match(line)
    assert match, line
    assert float(match["miss"]) < REACHED_M * 1e3
    with armfleet.connect(world.address) as client:
        reached = client.lookup("world", "bob_tool0")
    assert np.linalg.norm(reached[:3, 3] - (0.45, -0.1, 0.35)) < REACHED_M
    # roll 180 deg: tool z points down.
    assert np.allclose(reached[:3, 2], (0.0, 0.0, -1.0), atol=1e-3)
    (line,) = ok(runtime, "move", "bob", "--pose", "0.45", "0.1", "0.3", "--linear", "--wait")
    assert (match := POSE_LINE.match(line)) and float(match["miss"]) < REACHED_M * 1e3, line


def test_move_together_moves_both_arms(world: WorldProcess, runtime: Path) -> None:
    bob, toby = list(PANDA_HOME), list(PANDA_HOME)
    bob[0], toby[0] = 0.6, -0.1
    text = {name: ",".join(str(v) for v in q) for name, q in (("bob", bob), ("toby", toby))}
    (line,) = ok(runtime, "move-together", f"bob={text['bob']}", f"toby={text['toby']}", "--wait")
    assert re.match(r"^bob, toby: moved together in [0-9.]+ s; holding at t=[0-9.]+s$", line)
    with armfleet.connect(world.address) as client:
        assert np.abs(client.arm("bob").positions - bob).max() < HOLD_TOLERANCE_RAD
        assert np.abs(client.arm("toby").positions - toby).max() < HOLD_TOLERANCE_RAD


def test_objects_are_added_listed_and_removed(world: WorldProcess, runtime: Path) -> None:
    (added,) = ok(
        runtime, "add-object", "crate", "box", "--size", "0.1", "0.2", "0.05", "--mass", "0.3",
        "--at", "0.5", "0.6", "0.025", "--yaw", "30",
    )  # fmt: skip
    assert added == "crate: added, box (0.3 kg) at (0.500, 0.600, 0.025) m"
    ok(runtime, "add-object", "ball", "sphere", "--size", "0.03", "--at", "-0.5", "0.6", "0.03")
    header, *rows, footer = ok(runtime, "objects")
    assert header.split()[:3] == ["name", "shape", "mass"]
    assert [row.split()[:3] for row in rows] == [["crate", "box", "0.3"], ["ball", "sphere", "0.1"]]
    assert "+0.500, +0.600, +0.025" in rows[0] and rows[0].endswith("0.1 0.2 0.05")
    assert footer.startswith("(2 object(s); ")
    with armfleet.connect(world.address) as client:
        assert client.objects["crate"].rpy_deg[2] == pytest.approx(30.0, abs=0.1)
    assert ok(runtime, "remove-object", "crate", "ball") == ["crate: removed", "ball: removed"]
    header, footer = ok(runtime, "objects")
    assert footer.startswith("(0 object(s); ")


#: id -> (arguments, what the one error line says)
BAD: dict[str, tuple[list[str], str]] = {
    "grip-unknown-arm": (["grip", "zed", "open"], "no arm named 'zed'; arms: bob, toby, ur"),
    "grip-no-gripper": (["grip", "ur", "close"], "ur (ur3) has no gripper"),
    "grip-bad-action": (["grip", "bob", "wide"], "give open, close or a width (metres"),
    "grip-nan": (
        ["grip", "bob", "nan"],
        "gripper width nan m is invalid; give a value in [0, 0.08]",
    ),
    "grip-too-wide": (["grip", "bob", "0.2"], "give a value in [0, 0.08] m"),
    "grip-force": (["grip", "bob", "close", "--force", "-1"], "force -1 N is invalid"),
    "pose-unknown-arm": (["move", "zed", "--pose", "0.4", "0", "0.4"], "no arm named 'zed'"),
    "pose-count": (["move", "bob", "--pose", "0.4", "0"], "--pose takes X Y Z [ROLL PITCH YAW]"),
    "pose-count-5": (["move", "bob", "--pose", "0.4", "0", "0.4", "0", "0"], "got 5"),
    "pose-nan": (["move", "bob", "--pose", "0.4", "nan", "0.4"], "a pose must be finite"),
    "pose-unreachable": (["move", "bob", "--pose", "3", "0", "0.4"], "tool0 cannot reach the pose"),
    "pose-and-joints": (
        ["move", "bob", "--pose", "0.4", "0", "0.4", "--joints", "0"],
        "not allowed with argument --pose",
    ),
    "pose-unknown-link": (
        ["move", "bob", "--pose", "0.4", "0", "0.4", "--link", "hand"],
        "frame 'hand' not found; links of bob: base_link,",
    ),
    "pose-unknown-frame": (
        ["move", "bob", "--pose", "0.4", "0", "0.4", "--frame", "table"],
        "frame 'table' not found",
    ),
    "joints-with-link": (["move", "bob", "--joints", "0", "--link", "hand"], "goes with --pose"),
    "together-malformed": (["move-together", "bob"], "give NAME=Q1,Q2,..., one per arm"),
    "together-count": (["move-together", f"bob={HOME}", "toby=0,1"], "toby: got 2 target"),
    "together-nan": (
        ["move-together", f"bob={HOME}", "toby=nan" + HOME[1:]],
        "toby: target for toby_panda_joint1 is nan",
    ),
    "together-unknown": (["move-together", f"zed={HOME}"], "no arm named 'zed'"),
    "together-twice": (["move-together", f"bob={HOME}", f"bob={HOME}"], "given twice"),
    "object-shape": (["add-object", "cup", "cone", "--size", "0.1"], "invalid choice: 'cone'"),
    "object-size-count": (
        ["add-object", "cup", "cylinder", "--size", "0.1"],
        "size: got 1 numbers; a cylinder takes (radius, length)",
    ),
    "object-nan-mass": (
        ["add-object", "cup", "sphere", "--size", "0.1", "--mass", "nan"],
        "mass: nan is outside [0, 10000] kg",
    ),
    "object-at-count": (["add-object", "cup", "sphere", "--size", "0.1", "--at", "1", "2"], "--at"),
    "object-name-taken": (["add-object", "bob", "sphere", "--size", "0.1"], "'bob' is already"),
    "remove-unknown-object": (["remove-object", "cup"], "no object named 'cup'; objects: (none)"),
}


@pytest.fixture(scope="module")
def bad_runs(runtime: Path) -> dict[str, subprocess.CompletedProcess[str]]:
    """Every bad invocation, started together (each fails at once, touching nothing)."""
    ok(runtime, "move", "bob", "--joints", *HOME.split(","), "--wait")
    processes = {
        key: subprocess.Popen(
            [*ARMFLEET, *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=runtime_env(runtime),
        )
        for key, (args, _) in BAD.items()
    }
    results = {}
    for key, process in processes.items():
        stdout, stderr = process.communicate(timeout=120)
        results[key] = subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)
    return results


@pytest.mark.parametrize("key", list(BAD))
def test_a_bad_command_is_one_line_and_exit_2(
    bad_runs: dict[str, subprocess.CompletedProcess[str]], key: str
) -> None:
    result = bad_runs[key]
    assert result.returncode == 2
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("armfleet: error: ")
    assert BAD[key][1] in lines[0]


def test_after_the_bad_commands_the_world_steps_on_untouched(
    bad_runs: dict[str, subprocess.CompletedProcess[str]], world: WorldProcess
) -> None:
    with armfleet.connect(world.address) as client:
        start = client.info().time_s
        assert wait_until(lambda: client.info().time_s > start + 0.01)
        assert list(client.arms) == ["bob", "toby", "ur"]
        assert client.objects == {}
        bob = client.arm("bob")
        assert bob.mode is armfleet.ArmMode.HOLDING
        assert np.abs(bob.positions - PANDA_HOME).max() < HOLD_TOLERANCE_RAD
        assert client.info().streams == 0  # no failed command left a stream open
