"""A sweep's results path is checked before anything starts, as a recording's is: a
folder that takes no file, a results, journal or plot path that is a folder, one line
and exit 2, and Ray never imported."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.output_path import new_file_problem, results_path

ARMFLEET = [sys.executable, "-m", "armfleet.cli.main"]

BOX_SPEC = """\
world: {viewer: false}
objects:
  - {name: box, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 0.2, at_m: [0, 0, 0.05]}
"""
TASK = "def task(world, rng):\n    return {'t': world.time}\n"


def _sweep(folder: Path) -> Path:
    (folder / "box.yaml").write_text(BOX_SPEC)
    (folder / "task.py").write_text(TASK)
    path = folder / "sweep.yaml"
    path.write_text("spec: box.yaml\ntask: task.py\nruns: 2\n")
    return path


def test_a_folder_that_takes_no_file_is_refused() -> None:
    # /proc lets root "write" by its permission bits, but no file can be made in it.
    assert new_file_problem(Path("/proc")) is not None
    with pytest.raises(SweepError, match="folder '/proc' takes no new file"):
        results_path("/proc/x.parquet", resume=False, overwrite=False)


def test_a_writable_folder_is_left_as_it_was(tmp_path: Path) -> None:
    assert new_file_problem(tmp_path) is None
    assert results_path(tmp_path / "r.parquet", resume=False, overwrite=False) == (
        tmp_path / "r.parquet"
    )
    assert list(tmp_path.iterdir()) == []  # the probe file is gone


@pytest.mark.parametrize(
    ("folder_named", "words"),
    [
        ("r.parquet", "results file 'r.parquet' is a folder, not a regular file"),
        ("r.parquet.journal", "its journal 'r.parquet.journal' is a folder"),
        ("r.png", "its plot 'r.png' is a folder"),  # else written only after every run
    ],
)
def test_a_results_journal_or_plot_path_that_is_a_folder_is_refused(
    tmp_path: Path, folder_named: str, words: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / folder_named).mkdir()
    for flags in ({}, {"overwrite": True}, {"resume": True}):
        with pytest.raises(SweepError, match=words):
            results_path(
                "r.parquet",
                resume=flags.get("resume", False),
                overwrite=flags.get("overwrite", False),
            )


@pytest.mark.parametrize(
    ("output", "words"),
    [
        ("/proc/x.parquet", "folder '/proc' takes no new file"),
        ("/proc/version/x.parquet", "folder '/proc/version' is not a folder"),
        ("nowhere/x.parquet", "folder 'nowhere' not found"),
    ],
)
def test_armfleet_sweep_refuses_the_output_in_one_line_before_ray(
    tmp_path: Path, output: str, words: str
) -> None:
    sweep = _sweep(tmp_path)
    result = subprocess.run(
        [*ARMFLEET, "sweep", str(sweep), "-o", output],
        cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert words in lines[0] and "starting" not in result.stderr


def test_the_python_api_refuses_it_without_importing_ray(tmp_path: Path) -> None:
    sweep = _sweep(tmp_path)
    code = (
        "import sys, armfleet\n"
        "try:\n"
        f"    armfleet.sweep({str(sweep)!r}, output='/proc/x.parquet', progress=False)\n"
        "except armfleet.SweepError as exc:\n"
        "    print('refused:', exc)\n"
        "print('ray' in sys.modules)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    refused, ray_loaded = result.stdout.strip().splitlines()
    assert refused.startswith("refused: results file '/proc/x.parquet'")
    assert ray_loaded == "False"
