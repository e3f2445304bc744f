"""A 12-run ``reach`` sweep on a local Ray instance with 2 CPUs completes, and its rows
equal a plain in-process loop over the same seeds, bit for bit (parameters and metrics);
re-running one row gives it again."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq

import armfleet
from armfleet.sweeps import load_sweep, run_seed
from armfleet.sweeps.results_schema import SweepMetadata

#: Enough seeds for every arm count (2, 3 and 4 arms), batches on both of the two
#: workers, and arms that reach; every run is done twice (on Ray, then in the plain loop),
#: so more seeds only repeat the same comparison.
RUNS = 12


def same(a: Any, b: Any) -> bool:
    return a == b or (
        isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b)
    )


def test_a_reach_sweep_on_ray_equals_a_plain_loop(tmp_path: Path) -> None:
    output = tmp_path / "reach.parquet"
    result = armfleet.sweep("reach", runs=RUNS, workers=2, output=output, progress=False)

    table = pq.read_table(output)
    assert table.num_rows == RUNS and result.counts.finished == RUNS
    rows = {row["seed"]: row for row in table.to_pylist()}
    assert sorted(rows) == list(range(RUNS))
    metadata = SweepMetadata.from_schema(table.schema)
    assert metadata is not None
    assert set(metadata.parameters) == {"task.arm_count", "task.spacing_m"}
    assert {"reached_fraction", "max_tracking_error_rad", "stops"} <= set(metadata.metrics)
    assert {row["pid"] for row in rows.values()} != {os.getpid()}  # workers ran them
    assert len({row["pid"] for row in rows.values()}) >= 2  # two workers shared them
    assert {row["task.arm_count"] for row in rows.values()} == {2, 3, 4}

    definition = load_sweep("reach")
    task = definition.task.load()
    for seed in range(RUNS):  # the plain loop a user would write, in this process
        plain = run_seed(definition, seed, task)
        row = rows[seed]
        assert plain["ok"] and row["ok"], (plain["error"], row["error"])
        for column in metadata.parameters:
            assert same(plain[column], row[column]), (seed, column)
        for metric in metadata.metrics:
            assert same(plain["metrics"][metric], row[metric]), (seed, metric)
        assert row["sim_time_s"] == plain["sim_time_s"]  # the same simulation, step for step
    again = run_seed(definition, 7, task)  # one row re-run: the same metrics again
    assert again["metrics"] == {m: rows[7][m] for m in metadata.metrics}
    # physics, not bookkeeping: an arm that reached tracked its reference within 1 mrad
    reached = [row for row in rows.values() if row["reached_fraction"] == 1.0]
    assert reached and all(row["max_tracking_error_rad"] < 1e-3 for row in reached)
