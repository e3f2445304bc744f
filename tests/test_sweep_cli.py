"""``armfleet sweep`` as a subprocess: bad input gets one line and exit 2 before anything
starts; Ctrl-C keeps every finished run in a whole Parquet file, and ``--resume`` runs
only the missing seeds."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import polars as pl
import pyarrow.parquet as pq
import pytest

from armfleet.sweeps.results_file import journal_path, read_results

ARMFLEET = [sys.executable, "-m", "armfleet.cli.main"]

BOX_SPEC = """\
world: {viewer: false}
objects:
  - {name: box, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 0.2, at_m: [0, 0, 0.05]}
"""

#: About 0.3 s of wall time per run, so that an interrupt finds the sweep midway.
SLOW_TASK = """
import time

def slow(world, rng, *, mass_kg=0.2):
    world.run(0.05)
    time.sleep(0.3)
    return {"z_m": float(world.object("box").position[2]), "draw": float(rng.normal())}
"""


#: A task whose runs after the first few wait until the test opens the gate: the sweep
#: cannot finish before the test's Ctrl-C, however the machine is loaded.
GATED_TASK = """
import os, time, uuid

def gated(world, rng, *, mass_kg=0.2):
    world.run(0.05)
    started = {folder!r}
    open(os.path.join(started, uuid.uuid4().hex), "w").close()
    deadline = time.monotonic() + 120
    while len(os.listdir(started)) > 6 and not os.path.exists({gate!r}):
        if time.monotonic() > deadline:
            break
        time.sleep(0.05)
    return {{"z_m": float(world.object("box").position[2]), "draw": float(rng.normal())}}
"""


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def armfleet(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*ARMFLEET, *args], capture_output=True, text=True, timeout=120, cwd=cwd)


def write_sweep(folder: Path, lines: str) -> Path:
    (folder / "box.yaml").write_text(BOX_SPEC)
    (folder / "tasks.py").write_text(SLOW_TASK)
    path = folder / "sweep.yaml"
    path.write_text("spec: box.yaml\n" + lines)
    return path


@pytest.mark.parametrize(
    ("case", "words"),
    [
        ("unknown scenario", "unknown scenario: 'handvoer'; shipped scenarios: "),
        ("task not callable", "is a float, not a function"),
        ("outside the schema", "reach [0.5, 1.2], outside the valid range [0.01, 1]"),
        ("zero runs", "argument --runs: '0' is invalid"),
        ("unreachable address", "cannot reach a Ray cluster at ray://127.0.0.1:9"),
        ("no cluster for auto", "--address auto: no Ray cluster is running"),
        ("unknown plot parameter", "--plot-against 'mass': not a parameter of this sweep"),
    ],
)
def test_bad_input_is_one_line_and_exit_2_before_anything_starts(
    tmp_path: Path, case: str, words: str
) -> None:
    sweep = write_sweep(
        tmp_path,
        "task: tasks.py:slow\nrandomize:\n  task.mass_kg: {uniform: [0.1, 0.3]}\n",
    )
    args = {
        "unknown scenario": ["handvoer", "--runs", "3"],
        "task not callable": [
            str(_with_task(tmp_path, "armfleet.scenarios.handover:TOLERANCE_M")),
            "--runs",
            "3",
        ],
        "outside the schema": [str(_outside_schema(tmp_path)), "--runs", "3"],
        "zero runs": [str(sweep), "--runs", "0"],
        "unreachable address": [str(sweep), "--runs", "3", "--address", "ray://127.0.0.1:9"],
        "no cluster for auto": [str(sweep), "--runs", "3", "--address", "auto"],
        "unknown plot parameter": [str(sweep), "--runs", "3", "--plot-against", "mass"],
    }[case]
    result = armfleet("sweep", *args, "-o", "out.parquet", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert words in lines[0]
    assert not (tmp_path / "out.parquet").exists()  # nothing ran
    assert result.stdout == ""


def _with_task(folder: Path, task: str) -> Path:
    path = folder / "other.yaml"
    path.write_text(f"spec: handover\ntask: {task}\n")
    return path


def _outside_schema(folder: Path) -> Path:
    path = folder / "gains.yaml"
    path.write_text(
        "spec: handover\ntask: armfleet.scenarios.handover:handover\nrandomize:\n"
        "  arms.bob.controllers.position_controller.velocity_scaling: {uniform: [0.5, 1.2]}\n"
    )
    return path


def test_an_interrupted_sweep_keeps_its_runs_and_resume_runs_only_the_rest(
    tmp_path: Path,
) -> None:
    sweep = write_sweep(
        tmp_path, "task: gated.py:gated\nrandomize:\n  task.mass_kg: {uniform: [0.1, 0.3]}\n"
    )
    started, gate = tmp_path / "started", tmp_path / "open"
    started.mkdir()
    (tmp_path / "gated.py").write_text(GATED_TASK.format(folder=str(started), gate=str(gate)))
    results = tmp_path / "r.parquet"
    # The gate holds every run after the sixth until the Ctrl-C, so at most 6 finished and
    # 3 in flight (2 workers + 1 queued) can be kept: 12 runs leave some for --resume.
    runs = 12
    command = [*ARMFLEET, "sweep", str(sweep), "--runs", str(runs), "-o", str(results)]
    process = subprocess.Popen(
        [*command, "--workers", "2", "--batch-size", "1", "--quiet"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Ctrl-C reaches it as in a terminal, even where this test's parent ignores SIGINT
        # (a CI job started in the background with &, which Python children inherit).
        preexec_fn=_default_sigint,
    )
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline:  # wait for a few rows in the journal
        if journal_path(results).exists():
            try:
                if read_results(results).num_rows >= 4:
                    break
            except Exception:  # the journal's first batch is being written
                pass
        time.sleep(0.2)
    process.send_signal(signal.SIGINT)  # Ctrl-C
    gate.touch()  # the runs in flight finish, as a slow run would, and the sweep stops
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert "add --resume to run the rest" in stderr and "Traceback" not in stderr

    kept = pq.read_table(results)  # a whole Parquet file: the footer was written
    assert not journal_path(results).exists()
    seeds = kept.column("seed").to_pylist()
    assert 4 <= len(seeds) < runs and len(set(seeds)) == len(seeds)
    assert f"{len(seeds)} of {runs} runs kept" in stderr

    resumed = subprocess.run(
        [*command, "--resume", "--quiet"], cwd=tmp_path, capture_output=True, text=True, timeout=180
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"ran {runs - len(seeds)} runs (0 failed)" in resumed.stdout
    final = pq.read_table(results)
    assert sorted(final.column("seed").to_pylist()) == list(range(runs))
    before = {row["seed"]: row for row in kept.to_pylist()}
    for row in final.to_pylist():  # the kept runs were not run again: same wall time and pid
        if row["seed"] in before:
            assert row == before[row["seed"]]
    # pandas and polars read it as it is
    assert len(pd.read_parquet(results)) == runs
    frame = pl.read_parquet(results)
    assert frame.height == runs and frame["ok"].all()
    assert frame["task.mass_kg"].is_between(0.1, 0.3).all()
    assert (tmp_path / "r.png").stat().st_size > 10_000  # the plot, redrawn at the end

    again = armfleet("sweep", str(sweep), "--runs", str(runs), "-o", str(results), cwd=tmp_path)
    assert again.returncode == 2 and "exists; --resume runs the seeds it lacks" in again.stderr
