"""Recordings from the command line: ``--record RUN.mcap`` (also when interrupted or killed),
``armfleet info``, ``armfleet plot`` (the PNG is checked) and bad input."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from PIL import Image

from armfleet.cli.main import main
from armfleet.recording import open_recording
from armfleet.recording.plot import figure_size_px, output_paths
from tests.conftest import RecordedRun

ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")
TIMEOUT_S = 60.0
PANDA_ARM_JOINTS = 7
#: matplotlib's tab: colours of the reference, measured and error lines (RGB).
LINE_COLORS = {"reference": (31, 119, 180), "measured": (255, 127, 14), "error": (214, 39, 40)}


def start_spawn(cwd: Path, *extra: str) -> subprocess.Popen[str]:
    """``armfleet spawn bob`` in a new headless world (never a developer's running world)."""
    return subprocess.Popen(
        [*ARMFLEET, "spawn", "bob", "--at", "0,0", "--no-viewer", "--no-api", *extra],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ | {"XDG_RUNTIME_DIR": str(cwd)},
    )


def wait_for_line(process: subprocess.Popen[str], text: str) -> list[str]:
    assert process.stdout is not None
    lines = []
    deadline = time.monotonic() + TIMEOUT_S
    for line in process.stdout:
        lines.append(line)
        if text in line or time.monotonic() > deadline:
            break
    assert any(text in line for line in lines), lines
    return lines


def run_main(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    try:
        code = main(args)
    except SystemExit as exc:
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


# -- --record RUN.mcap -------------------------------------------------------------------
def test_ctrl_c_leaves_a_complete_recording(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    process = start_spawn(tmp_path, "--record", str(path))
    wait_for_line(process, "ready in")
    time.sleep(0.5)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=TIMEOUT_S)
    assert process.returncode == 0, stderr
    assert f"recording saved to {path}" in stdout
    assert "interrupted; shut down cleanly" in stdout
    with path.open("rb") as stream:  # the mcap library reads it through its summary
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        topics = {c.topic for c in summary.channels.values()}
        assert {"/bob/joint_states", "/tf", "/tf_static", "/bringup"} <= topics
        states = [m for _, _, m in reader.iter_messages(topics=["/bob/joint_states"])]
    # Every step's state up to the interrupt, none lost: one per 1 ms of simulated time
    # (how many steps the machine managed in the 0.5 s is its own business).
    assert len(states) > 10
    span_ms = (states[-1].log_time - states[0].log_time) / 1e6
    assert len(states) == round(span_ms) + 1
    recording = open_recording(path)
    assert recording.complete and recording.arm_names == ("bob",)
    assert "bob" in (recording.spec_text or "")


def test_a_killed_run_leaves_a_readable_recording(tmp_path: Path) -> None:
    """kill -9 (no clean-up at all): the file reads back up to its last written chunk."""
    path = tmp_path / "killed.mcap"
    process = start_spawn(tmp_path, "--record", str(path), "--fast")
    wait_for_line(process, "ready in")
    deadline = time.monotonic() + TIMEOUT_S
    while path.stat().st_size < 1_000_000 and time.monotonic() < deadline:
        time.sleep(0.1)  # a few chunks written
    process.kill()
    process.communicate(timeout=TIMEOUT_S)
    recording = open_recording(path)
    assert not recording.complete
    assert recording.arm_names == ("bob",)
    count = recording.topics["/bob/joint_states"].message_count
    assert count > 1000
    times = [m.log_time_ns for m in recording.messages(["/bob/joint_states"])]
    assert len(times) == count and times == sorted(times)


# -- armfleet info -----------------------------------------------------------------------
def test_info_describes_a_recording(
    recorded_run: RecordedRun, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, err = run_main(["info", str(recorded_run.path)], capsys)
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].startswith(f"file:        {recorded_run.path}") and "complete" in lines[0]
    assert any(
        line.startswith("arms:        bob (panda at (0, 0, 0, yaw 0 deg)), toby (panda")
        for line in lines
    )
    assert any("duration 2.0" in line for line in lines)
    rows = {line.split()[0]: line.split() for line in lines if line.startswith("  /")}
    assert set(rows) >= set(recorded_run.topics)
    joint_states = rows["/bob/joint_states"]
    assert joint_states[1] == "sensor_msgs/msg/JointState"
    assert joint_states[3:] == ["1000.0", "Hz"]
    assert rows["/collisions"][2] == "0"


# -- armfleet plot -----------------------------------------------------------------------
def check_plot(path: Path, joints: int = PANDA_ARM_JOINTS) -> None:
    """Not blank, the expected size, and the three line colours drawn."""
    with Image.open(path) as image:
        assert image.size == figure_size_px(joints)
        pixels = np.asarray(image.convert("RGB")).reshape(-1, 3).astype(int)
    assert pixels.std() > 20  # not a flat image
    background = np.all(pixels > 245, axis=1).mean()
    assert 0.3 < background < 0.97, background  # mostly white paper, yet drawn on
    for name, color in LINE_COLORS.items():
        near = np.all(np.abs(pixels - color) < 30, axis=1).sum()
        assert near > 500, f"{name} line ({color}) missing: {near} pixels"


def test_plot_writes_one_figure_per_arm(
    recorded_run: RecordedRun, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, err = run_main(
        ["plot", str(recorded_run.path), "-o", str(tmp_path / "t.png")], capsys
    )
    assert code == 0, err
    bob, toby = tmp_path / "t_bob.png", tmp_path / "t_toby.png"
    assert out.splitlines() == [f"bob: {bob}", f"toby: {toby}"]
    check_plot(bob)
    with Image.open(toby) as image:  # toby holds still: the same size, flat lines
        assert image.size == figure_size_px(PANDA_ARM_JOINTS)


def test_plot_file_names() -> None:
    run = Path("/runs/run.mcap")
    assert output_paths(run, ["bob", "toby"], None) == {
        "bob": Path("/runs/run_bob.png"),
        "toby": Path("/runs/run_toby.png"),
    }
    assert output_paths(run, ["bob"], "/out/b.svg") == {"bob": Path("/out/b.svg")}
    assert output_paths(run, ["bob", "toby"], "/out/b.pdf")["toby"] == Path("/out/b_toby.pdf")
    folder = Path(__file__).parent  # an existing folder: the default names in it
    assert output_paths(run, ["bob"], folder) == {"bob": folder / "run_bob.png"}


# -- bad input ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def not_mcap(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("bad") / "notes.mcap"
    path.write_text("these are notes, not a recording\n")
    return path


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["info", "{missing}"], "no recording at {missing}: the file does not exist"),
        (["plot", "{missing}"], "no recording at {missing}"),
        (["replay", "{missing}"], "no recording at {missing}"),
        (["info", "{not_mcap}"], "{not_mcap} is not an MCAP recording"),
        (["plot", "{not_mcap}"], "is not an MCAP recording"),
        (["plot", "{run}", "--arm", "bobby"], "has no arm named 'bobby'; arms: bob, toby"),
        (["plot", "{run}", "-o", "{tmp}/plot.jpg"], "name a .png, .svg, .pdf file"),
        (["replay", "{run}", "--html", "{tmp}/out.htm"], "--html {tmp}/out.htm: name an .html"),
        (["replay", "{run}", "--speed", "0"], "--speed: '0' is invalid"),
        (["replay", "{run}", "--speed", "nan"], "--speed: 'nan' is invalid"),
        (["info", "{run}", "--connect", "tcp://127.0.0.1:9"], "a recording or --connect"),
        (
            ["spawn", "bob", "--at", "0,0", "--record", "run.bag"],
            "--record run.bag: name a .mcap or .html file",
        ),
        (
            ["launch", "bob_and_toby", "--record", "{tmp}/no/such/folder/run.mcap"],
            "the folder {tmp}/no/such/folder does not exist",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    args: list[str],
    expected: str,
    recorded_run: RecordedRun,
    not_mcap: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    values = {
        "missing": str(tmp_path / "missing.mcap"),
        "not_mcap": str(not_mcap),
        "run": str(recorded_run.path),
        "tmp": str(tmp_path),
    }
    code, out, err = run_main([arg.format(**values) for arg in args], capsys)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("armfleet: error: "), err
    assert expected.format(**values) in err
    assert "Traceback" not in err


def test_bad_input_from_a_real_process(tmp_path: Path) -> None:
    """The same one line and exit code 2 from the installed command."""
    result = subprocess.run(
        [*ARMFLEET, "plot", str(tmp_path / "nope.mcap")],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert result.returncode == 2
    assert result.stderr == (
        f"armfleet: error: no recording at {tmp_path / 'nope.mcap'}: the file does not exist\n"
    )
