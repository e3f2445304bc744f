"""A run's time limit is wall time for its task alone: the world's bring-up has a limit of
its own and never shortens the task's; the summary says how many runs the limit ended."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from armfleet.sweeps.definition import SweepDefinition, load_sweep
from armfleet.sweeps.run import run_seed
from armfleet.sweeps.summary import summarize
from tests.test_sweep_report import results_table

BOX_SPEC = """\
world: {viewer: false}
objects:
  - {name: box, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 0.2, at_m: [0, 0, 0.05]}
"""

#: Loading the file (part of the bring-up) and the task each take a known wall time.
SLOW_TASK = """
import time

time.sleep({load_s})

def task(world, rng):
    time.sleep({task_s})
    world.run(0.05)
    return {{"z_m": float(world.object("box").position[2])}}
"""


def _definition(folder: Path, load_s: float, task_s: float, limit_s: float) -> SweepDefinition:
    (folder / "box.yaml").write_text(BOX_SPEC)
    (folder / "slow.py").write_text(SLOW_TASK.format(load_s=load_s, task_s=task_s))
    sweep = folder / "sweep.yaml"
    sweep.write_text(f"spec: box.yaml\ntask: slow.py\nrun_timeout_s: {limit_s}\n")
    definition = load_sweep(sweep)  # loads the file once, here
    for name in [m for m in sys.modules if m.startswith("armfleet_sweep_task_")]:
        del sys.modules[name]  # so that the run loads it again, as a fresh worker does
    return definition


def test_the_bringup_does_not_count_against_the_tasks_limit(tmp_path: Path) -> None:
    """1.5 s of bring-up and 2.0 s of task under a 3 s limit: each part is within it,
    their sum is not (a limit over the whole run failed this run)."""
    definition = _definition(tmp_path, load_s=1.5, task_s=2.0, limit_s=3.0)
    row = run_seed(definition, 0)
    assert row["ok"], row["error"]
    assert row["bringup_s"] >= 1.5 and row["task_s"] >= 2.0 and row["wall_s"] > 3.0
    assert abs(row["metrics"]["z_m"] - 0.05) < 2e-3  # the box rests on the floor


def test_a_task_past_its_limit_is_a_failed_row_that_says_wall_time(tmp_path: Path) -> None:
    definition = _definition(tmp_path, load_s=0.0, task_s=5.0, limit_s=1.0)
    row = run_seed(definition, 0)
    assert not row["ok"]
    assert row["error"].startswith("RunTimedOut: the run's task took longer than its limit")
    assert "1 s of wall time" in row["error"]
    assert row["bringup_s"] is not None and row["task_s"] is None and row["wall_s"] < 5.0


def test_a_bringup_past_the_limit_is_a_failed_row_of_its_own(tmp_path: Path) -> None:
    definition = _definition(tmp_path, load_s=3.0, task_s=0.0, limit_s=1.0)
    row = run_seed(definition, 0)
    assert not row["ok"]
    assert row["error"].startswith("RunTimedOut: the run's bring-up took longer")
    assert row["bringup_s"] is None and row["wall_s"] < 3.0


def test_the_summary_counts_the_runs_the_time_limit_ended() -> None:
    errors = [
        "RunTimedOut: the run's task took longer than its limit of 60 s of wall time",
        "RunTimedOut: the run's bring-up took longer than its limit of 60 s of wall time",
        "RunTimedOut: the worker did not return within 150 s",
        "ValueError: the task failed",
        None,
        None,
    ]
    ok = np.array([error is None for error in errors])
    summary = summarize(results_table(ok, errors=errors))
    assert summary.failed_runs == 4 and summary.timed_out_runs == 3
    text = summary.format()
    assert "ended by the time limit: 3 runs (run_timeout_s is wall time" in text
    assert "ended by the time limit: 0 runs" in summarize(results_table([True, True])).format()
