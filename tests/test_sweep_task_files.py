"""A sweep's task named as a file without ``:function``, as docs/sweeps.md documents it:
``file.py`` (or ``file.py:``) means its function ``task``, or its only function; from
the sweep file to a Parquet row, through ``armfleet sweep``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from armfleet.spec import SpecError
from armfleet.sweeps.definition import load_sweep

ARMFLEET = [sys.executable, "-m", "armfleet.cli.main"]

BOX_SPEC = """\
world: {viewer: false}
objects:
  - {name: box, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 0.2, at_m: [0, 0, 0.05]}
"""

#: A file whose function is called ``task``, beside a helper it imports.
NAMED_TASK = """
from math import isfinite

def task(world, rng, *, drop_m=0.0):
    world.run(0.2)
    z = float(world.object("box").position[2])
    return {"rest_z_m": z, "finite": isfinite(z)}
"""

#: The docs' example: a file with one function, not called ``task``.
ONLY_FUNCTION = """
import numpy as np

def drop_box(world, rng, *, height_m=0.3):
    world.run(0.2)
    return {"rest_z_m": float(world.object("box").position[2]), "height_m": height_m}
"""

TWO_FUNCTIONS = """
def first(world, rng):
    return {}

def second(world, rng):
    return {}
"""


def _sweep_file(folder: Path, task: str, randomize: str = "") -> Path:
    (folder / "box.yaml").write_text(BOX_SPEC)
    path = folder / "sweep.yaml"
    path.write_text(f'spec: box.yaml\ntask: "{task}"\nruns: 2\n' + randomize)
    return path


@pytest.mark.parametrize(
    ("source", "task", "function"),
    [
        (NAMED_TASK, "named.py", "task"),
        (NAMED_TASK, "named.py:", "task"),  # nothing after the colon: the default too
        (ONLY_FUNCTION, "drop.py", "drop_box"),  # no task(): the one function it defines
        (ONLY_FUNCTION, "drop.py:", "drop_box"),
        (ONLY_FUNCTION, "drop.py:drop_box", "drop_box"),
    ],
)
def test_a_task_file_without_a_function_name_is_its_task(
    tmp_path: Path, source: str, task: str, function: str
) -> None:
    (tmp_path / task.split(":")[0]).write_text(source)
    definition = load_sweep(_sweep_file(tmp_path, task))
    loaded = definition.task.load()
    assert loaded.__name__ == function
    assert definition.task.module is None and definition.task.source == source


def test_a_file_with_no_task_and_several_functions_asks_for_one(tmp_path: Path) -> None:
    (tmp_path / "two.py").write_text(TWO_FUNCTIONS)
    with pytest.raises(SpecError) as error:
        load_sweep(_sweep_file(tmp_path, "two.py"))
    message = str(error.value)
    assert "no function 'task' in it" in message and "first, second" in message
    assert "two.py:function" in message and "''" not in message


def test_armfleet_sweep_runs_a_task_file_named_without_a_function(tmp_path: Path) -> None:
    """End to end: the docs' one-function file, named ``drop.py``, gives a row per run
    whose metrics are the physics' (the box rests on the floor, its half-size up)."""
    (tmp_path / "drop.py").write_text(ONLY_FUNCTION)
    sweep = _sweep_file(tmp_path, "drop.py", "randomize:\n  task.height_m: {uniform: [0.2, 0.4]}\n")
    result = subprocess.run(
        [*ARMFLEET, "sweep", str(sweep), "--workers", "1", "-o", "out.parquet"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    # A sign of life before Ray's seconds of start-up, and no unexplained counter.
    assert "sweep: 2 runs; starting a private local Ray instance" in result.stderr
    assert "kept=" not in result.stderr
    rows = pq.read_table(tmp_path / "out.parquet").to_pylist()
    assert sorted(row["seed"] for row in rows) == [0, 1]
    for row in rows:
        assert row["ok"], row["error"]
        assert row["rest_z_m"] == pytest.approx(0.05, abs=2e-3)  # half of 0.1 m
        assert row["height_m"] == row["task.height_m"]  # the drawn keyword reached it
        assert 0.2 <= row["task.height_m"] < 0.4
