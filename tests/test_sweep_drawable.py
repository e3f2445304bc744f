"""Every distribution is one NumPy's generator can draw from, checked before Ray starts;
and a draw that fails anyway is a failed row, never a sweep that crashes or hangs."""

from __future__ import annotations

import subprocess
import sys
import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

from armfleet.sweeps.definition import load_sweep
from armfleet.sweeps.distributions import Distribution, DistributionError, parse_distribution
from armfleet.sweeps.randomization import RandomParameter
from armfleet.sweeps.run import run_seed
from armfleet.sweeps.runner import failed_row

ARMFLEET = [sys.executable, "-m", "armfleet.cli.main"]
INT64_MAX = 2**63 - 1

BOX_SPEC = """\
world: {viewer: false}
objects:
  - {name: box, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 0.2, at_m: [0, 0, 0.05]}
"""
TASK = "def task(world, rng, *, k=0):\n    return {'k': int(k)}\n"


def _sweep(folder: Path, randomize: str) -> Path:
    (folder / "box.yaml").write_text(BOX_SPEC)
    (folder / "task.py").write_text(TASK)
    path = folder / "sweep.yaml"
    path.write_text(f"spec: box.yaml\ntask: task.py\nruns: 3\nrandomize:\n  task.k: {randomize}\n")
    return path


@pytest.mark.parametrize(
    ("entry", "words"),
    [
        ({"integers": [0, 1e30]}, "outside what can be drawn, the int64 range"),
        ({"integers": [0, 2**63]}, "outside what can be drawn, the int64 range"),
        ({"integers": [-(2**63) - 1, 0]}, "outside what can be drawn, the int64 range"),
        ({"integers": [[0, 0], [5, 1e19]]}, "outside what can be drawn, the int64 range"),
        ({"integers": [0, 10**400]}, "is not a finite number"),
        ({"integers": [0.5, 3]}, "0.5 is not a whole number"),
        ({"integers": [2**62 + 1, 2**62]}, "is above high"),  # equal as floats, not as ints
        ({"uniform": [-1e308, 1e308]}, "high - low overflows"),
        ({"normal": [1e308, 1e307]}, "could overflow to infinity"),
        ({"normal": [0.0, 1e307]}, "could overflow to infinity"),
    ],
)
def test_a_distribution_numpy_cannot_draw_from_is_refused(entry: object, words: str) -> None:
    with pytest.raises(DistributionError, match=words) as error:
        parse_distribution(entry)
    assert len(str(error.value)) < 200  # one line, even for a 400-digit number


def test_the_int64_range_is_drawn_exactly() -> None:
    """Bounds above 2^53 are not rounded to floats: every draw is one of the three whole
    numbers asked for, as NumPy's own generator on the same stream gives them."""
    low = 2**62 + 1
    distribution, _ = parse_distribution({"integers": [low, low + 2]})
    parameter = RandomParameter("task.k", distribution)
    for seed in range(20):
        value = parameter.draw(seed)
        stream = np.random.default_rng([seed, zlib.crc32(b"task.k")])
        expected = int(stream.integers(low, low + 2, endpoint=True))
        assert isinstance(value, int) and value == expected and low <= value <= low + 2
    widest, _ = parse_distribution({"integers": [-(2**63), INT64_MAX]})
    assert -(2**63) <= int(RandomParameter("task.k", widest).draw(0)) <= INT64_MAX  # type: ignore[arg-type]
    top, _ = parse_distribution({"integers": [INT64_MAX, INT64_MAX]})
    assert RandomParameter("task.k", top).draw(3) == INT64_MAX


def test_armfleet_sweep_refuses_an_undrawable_distribution_in_one_line(tmp_path: Path) -> None:
    sweep = _sweep(tmp_path, "{integers: [0, 1e30]}")
    result = subprocess.run(
        [*ARMFLEET, "sweep", str(sweep), "-o", "out.parquet"],
        cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert "sweep.yaml:5" in lines[0] and "int64 range" in lines[0]
    assert "starting" not in result.stderr  # refused before Ray was started
    assert not (tmp_path / "out.parquet").exists()


@dataclass(frozen=True)
class _Undrawable(Distribution):
    """A distribution whose draw fails, as one the checks missed would in a worker."""

    size: int = 0

    def draw(self, rng: np.random.Generator) -> float:
        raise ValueError("high < 0")

    def support(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(1), np.ones(1)


def test_a_draw_that_fails_is_a_failed_row_not_a_crash(tmp_path: Path) -> None:
    definition = load_sweep(_sweep(tmp_path, "{integers: [0, 5]}"))
    broken = replace(definition, randomization=(RandomParameter("task.k", _Undrawable()),))
    row = run_seed(broken, 7)  # in a worker: the row says why
    assert row["seed"] == 7 and row["ok"] is False and row["metrics"] == {}
    assert row["error"].startswith("ValueError: high < 0")
    # In the driver, for a batch Ray gave up on: the row, its drawn columns left empty.
    driver_row = failed_row(broken, 7, "WorkerCrashedError: the worker died")
    assert driver_row["ok"] is False and driver_row["error"].startswith("WorkerCrashedError")
    assert driver_row.get("task.k") is None
