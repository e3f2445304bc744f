"""The report of a sweep's results: summary numbers, the figure, ``armfleet sweep-report``.

Every expected value is known independently of the code under test: synthetic tables whose
truth is built in, published Wilson intervals, percentiles worked by hand or by numpy.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from matplotlib.image import imread

from armfleet.cli.sweep_report_command import run as run_command
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.report_plot import (
    DPI,
    PANEL_IN,
    bin_groups,
    explained_variance,
    plot_sweep,
    sweep_panels,
)
from armfleet.sweeps.results_file import read_results
from armfleet.sweeps.results_schema import METADATA_KEY, RUN_COLUMNS, SweepMetadata
from armfleet.sweeps.summary import Z_95, summarize, wilson_interval

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def results_table(
    ok: list[bool] | np.ndarray,
    parameters: dict[str, np.ndarray] | None = None,
    metrics: dict[str, pa.Array] | None = None,
    errors: list[str | None] | None = None,
    wall_s: np.ndarray | None = None,
) -> pa.Table:
    """A sweep's results as a sweep writes them: run columns, parameters, metrics, metadata."""
    ok = np.asarray(ok, dtype=bool)
    n = ok.size
    parameters = parameters or {}
    metrics = metrics or {}
    if errors is None:
        errors = [None if row_ok else "RuntimeError: the run failed" for row_ok in ok]
    run_values: dict[str, pa.Array] = {
        "seed": pa.array(np.arange(100, 100 + n), pa.int64()),
        "ok": pa.array(ok, pa.bool_()),
        "error": pa.array(errors, pa.string()),
        "wall_s": pa.array(np.full(n, 2.0) if wall_s is None else wall_s, pa.float64()),
        "bringup_s": pa.array(np.full(n, 0.5), pa.float64()),
        "task_s": pa.array(np.full(n, 1.25), pa.float64()),
        "stepping_s": pa.array(np.full(n, 1.0), pa.float64()),
        "sim_time_s": pa.array(np.full(n, 4.0), pa.float64()),
        "host": pa.array(["worker"] * n, pa.string()),
        "pid": pa.array(np.full(n, 4242), pa.int64()),
    }
    assert list(run_values) == list(RUN_COLUMNS)
    columns = {**run_values, **{name: pa.array(v) for name, v in parameters.items()}, **metrics}
    metadata = SweepMetadata(
        scenario="synthetic",
        spec="synthetic.yaml",
        task="tests:task",
        base_seed=100,
        runs=n,
        parameters=tuple(parameters),
        metrics=tuple(metrics),
    )
    return pa.table(columns).replace_schema_metadata({METADATA_KEY: metadata.to_json()})


def linear_sweep(n: int = 400, failed: int = 0) -> pa.Table:
    """``y = 3 x1 + noise`` (sigma 0.05), ``x2`` unrelated; ``z`` depends on ``x2`` only;
    ``success`` is ``x1 > 0.5``. The first ``failed`` runs failed (metrics null)."""
    rng = np.random.default_rng(7)
    x1 = rng.uniform(0.0, 1.0, n)
    x2 = rng.uniform(-1.0, 1.0, n)
    ok = np.arange(n) >= failed
    y = 3.0 * x1 + rng.normal(0.0, 0.05, n)
    z = np.sin(3.0 * x2) + rng.normal(0.0, 0.05, n)
    return results_table(
        ok,
        parameters={"x1": x1, "x2": x2},
        metrics={
            "y": pa.array(np.where(ok, y, np.nan), pa.float64(), mask=~ok),
            "z": pa.array(np.where(ok, z, np.nan), pa.float64(), mask=~ok),
            "success": pa.array(x1 > 0.5, pa.bool_(), mask=~ok),
        },
    )


def assert_real_png(path: Path) -> np.ndarray:
    """The image at ``path``, after checking it is a PNG with something drawn on it."""
    assert path.read_bytes()[:8] == PNG_SIGNATURE
    image = imread(path)
    assert image.ndim == 3 and image.shape[0] > 50 and image.shape[1] > 50
    assert float(image[..., :3].var()) > 0.0, "the image is blank"
    return image


# -- Wilson score interval ------------------------------------------------------------


@pytest.mark.parametrize(
    ("successes", "n", "low", "high"),
    [
        # z^2 / (n + z^2) for none and all of 10 (the closed form at the ends).
        (0, 10, 0.0, 0.2775),
        (10, 10, 0.7225, 1.0),
        # Newcombe (1998), Statistics in Medicine 17:857, Table I, method 3 (score).
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ],
)
def test_wilson_interval_matches_published_values(
    successes: int, n: int, low: float, high: float
) -> None:
    got_low, got_high = wilson_interval(successes, n)
    # The published values have 4 decimals: half a unit of the last one, and a little.
    assert got_low == pytest.approx(low, abs=6e-5)
    assert got_high == pytest.approx(high, abs=6e-5)


@pytest.mark.parametrize(("successes", "n"), [(1, 7), (13, 40), (99, 100), (500, 1000)])
def test_wilson_bounds_are_where_the_score_test_is_at_z(successes: int, n: int) -> None:
    """The interval is every p whose score statistic |p_hat - p| / sqrt(p (1-p) / n) is at
    most z: its ends solve the equality."""
    p_hat = successes / n
    for p in wilson_interval(successes, n):
        assert abs(p_hat - p) / math.sqrt(p * (1.0 - p) / n) == pytest.approx(Z_95, rel=1e-9)


def test_wilson_interval_of_no_trials_is_everything() -> None:
    assert wilson_interval(0, 0) == (0.0, 1.0)


# -- summary ----------------------------------------------------------------------------


def test_numeric_metric_percentiles_over_ok_rows_only() -> None:
    """101 ok runs hold 1..101 (shuffled): linear interpolation puts p5 at the 6th value,
    the median at the 51st, p95 at the 96th. Failed runs hold junk, which must not count."""
    rng = np.random.default_rng(3)
    values = rng.permutation(np.arange(1.0, 102.0))
    ok = np.concatenate([np.ones(101, bool), np.zeros(4, bool)])
    junk = np.concatenate([values, np.full(4, 1e9)])
    table = results_table(ok, metrics={"error_m": pa.array(junk, pa.float64())})
    (distribution,) = summarize(table).numeric
    assert distribution.name == "error_m"
    assert distribution.n == 101
    assert (distribution.p5, distribution.median, distribution.p95) == (6.0, 51.0, 96.0)


def test_numeric_metric_percentiles_match_numpy_and_skip_nulls() -> None:
    rng = np.random.default_rng(11)
    values = rng.lognormal(0.0, 1.0, 57)
    nulls = np.zeros(57, bool)
    nulls[::5] = True  # an ok run may leave a metric out
    table = results_table(
        np.ones(57, bool), metrics={"time_s": pa.array(values, pa.float64(), mask=nulls)}
    )
    (distribution,) = summarize(table).numeric
    kept = values[~nulls]
    assert distribution.n == kept.size
    expected = np.percentile(kept, [5.0, 50.0, 95.0])
    got = [distribution.p5, distribution.median, distribution.p95]
    np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_integer_metric_is_numeric() -> None:
    table = results_table([True] * 4, metrics={"contacts": pa.array([1, 2, 3, 10], pa.int64())})
    (distribution,) = summarize(table).numeric
    assert distribution.median == 2.5


def test_success_metric_counts_a_failed_run_as_not_successful() -> None:
    ok = [True] * 8 + [False] * 2
    success = [True] * 6 + [False] * 2 + [None, None]
    table = results_table(ok, metrics={"success": pa.array(success, pa.bool_())})
    summary = summarize(table)
    assert (summary.success.name, summary.success.successes, summary.success.n) == (
        "success",
        6,
        10,
    )
    assert summary.rates == ()  # success is not listed again among the other rates


def test_success_is_ok_without_a_success_metric() -> None:
    ok = [True] * 8 + [False] * 2
    table = results_table(ok, metrics={"reached": pa.array([True] * 3 + [False] * 5 + [None] * 2)})
    summary = summarize(table)
    assert (summary.success.name, summary.success.successes, summary.success.n) == ("ok", 8, 10)
    assert (summary.runs, summary.ok_runs, summary.failed_runs) == (10, 8, 2)
    # Another bool metric: its rate over the ok runs that have it, 3 of 8.
    (reached,) = summary.rates
    assert (reached.name, reached.successes, reached.n) == ("reached", 3, 8)
    assert reached.rate == pytest.approx(3 / 8)


def test_three_most_common_errors_with_counts() -> None:
    errors = ["A: 1"] * 4 + ["B: 2"] * 3 + ["C: 3"] * 2 + ["D: 4"]
    table = results_table([False] * 10 + [True], errors=[*errors, None])
    summary = summarize(table)
    assert summary.failed_runs == 10
    assert summary.common_errors == (("A: 1", 4), ("B: 2", 3), ("C: 3", 2))


def test_wall_times() -> None:
    """wall_s 1..11: median 6, p95 at rank 0.95 * 10 = 9.5, between 10 and 11."""
    table = results_table([True] * 11, wall_s=np.arange(1.0, 12.0))
    wall = summarize(table).wall
    assert (wall.median_s, wall.p95_s) == (6.0, 10.5)
    assert (wall.mean_bringup_s, wall.mean_task_s, wall.mean_stepping_s) == (0.5, 1.25, 1.0)


def test_format_shows_every_number() -> None:
    ok = [True] * 8 + [False] * 2
    table = results_table(
        ok,
        metrics={
            "success": pa.array([True] * 6 + [False] * 2 + [None] * 2),
            "grasped": pa.array([True] * 4 + [False] * 4 + [None] * 2),
            "error_m": pa.array([0.5] * 8 + [None] * 2, pa.float64()),
            "note": pa.array(["fine"] * 8 + [None] * 2),
        },
        errors=[None] * 8 + ["TimeoutError: the gripper never closed"] * 2,
    )
    text = summarize(table).format()
    low, high = wilson_interval(6, 10)
    assert "10 runs, 8 ok, 2 failed" in text
    assert "2  TimeoutError: the gripper never closed" in text
    assert f"0.600 [{low:.3f}, {high:.3f}]" in text
    assert "6 of 10" in text
    assert any(line.split()[:2] == ["error_m", "8"] for line in text.splitlines())
    assert any(line.split()[:4] == ["grasped", "8", "4", "0.500"] for line in text.splitlines())
    assert "note" in text  # named as not summarized
    assert "median 2" in text and "bring-up 0.5" in text


def test_summary_of_no_runs() -> None:
    table = results_table([], metrics={"success": pa.array([], pa.bool_())})
    summary = summarize(table)
    assert (summary.runs, summary.success.n) == (0, 0)
    assert math.isnan(summary.success.rate) and math.isnan(summary.wall.median_s)
    assert "0 runs" in summary.format()


def test_summary_refuses_a_table_without_sweep_metadata() -> None:
    table = linear_sweep(10).replace_schema_metadata(None)
    with pytest.raises(SweepError, match="not an armfleet sweep's results"):
        summarize(table)


# -- eta^2 and the figure's panels ----------------------------------------------------------


def test_explained_variance_worked_by_hand() -> None:
    """Two groups (x = 0, 1) with means 2 and 6 around a grand mean of 4: between-group sum
    of squares 2 * 4 + 2 * 4 = 16, total (9 + 1 + 1 + 9) = 20."""
    assert explained_variance([0, 0, 1, 1], [1, 3, 5, 7]) == pytest.approx(0.8)
    assert explained_variance([0, 1, 0, 1], [1, 3, 5, 7]) == pytest.approx(0.2)
    assert explained_variance([0, 1, 2, 3], [5, 5, 5, 5]) == 0.0  # nothing to explain
    assert explained_variance([1, 1, 1, 1], [1, 3, 5, 7]) == 0.0  # one bin explains nothing


def test_quantile_bins_merge_identical_edges() -> None:
    """Six tenths of the values are 0: the quantile edges at 0 coincide and make one bin."""
    rng = np.random.default_rng(5)
    x = np.concatenate([np.zeros(600), rng.uniform(1.0, 2.0, 400)])
    groups = bin_groups(x)
    assert len(set(groups[x == 0.0])) == 1
    assert 2 <= len(set(groups)) <= 10
    assert not np.isin(groups[x == 0.0], groups[x > 0.0]).any()
    order = np.argsort(x, kind="stable")
    assert np.all(np.diff(groups[order]) >= 0)  # bins in increasing x


def test_each_metric_is_plotted_against_the_parameter_that_explains_it() -> None:
    table = linear_sweep()
    x1 = table.column("x1").to_numpy()
    x2 = table.column("x2").to_numpy()
    y = table.column("y").to_numpy()
    assert explained_variance(x1, y) > 0.9
    assert explained_variance(x2, y) < 0.1  # noise over 400 runs: about 9 / 400
    panels = {panel.metric: panel for panel in sweep_panels(table)}
    assert set(panels) == {"y", "z", "success"}  # no failed run: no panel of ok
    assert (panels["y"].x_name, panels["z"].x_name, panels["success"].x_name) == (
        "x1",
        "x2",
        "x1",
    )
    assert panels["y"].eta2 > 0.9 and panels["z"].eta2 > 0.9
    assert panels["success"].eta2 > 0.5  # a step at 0.5: 8 of 10 bins are pure


def test_failed_rows_are_left_out_of_numeric_panels() -> None:
    """Failed runs carrying a (wrong) metric value of 1e9 must not be drawn."""
    table = linear_sweep(200, failed=30)
    junk = pa.array(np.full(200, 1e9), pa.float64())
    table = table.set_column(table.column_names.index("y"), "y", junk)
    panels = {panel.metric: panel for panel in sweep_panels(table)}
    assert panels["y"].y.size == 170
    assert panels["z"].y.size == 170
    # success counts every run (a failed one as not successful), and ok gets a panel.
    assert panels["success"].y.size == 200 and panels["ok"].y.size == 200
    assert panels["ok"].y.sum() == 170


def test_plot_against_a_given_parameter() -> None:
    panels = sweep_panels(linear_sweep(100), plot_against="x2")
    assert [panel.x_name for panel in panels] == ["x2"] * 3


def test_plot_against_an_unknown_parameter_lists_the_parameters() -> None:
    with pytest.raises(SweepError) as caught:
        sweep_panels(linear_sweep(20), plot_against="x3")
    message = str(caught.value)
    assert "'x3'" in message and "x1, x2" in message and "\n" not in message


def test_without_parameters_metrics_are_plotted_against_the_seed() -> None:
    table = results_table([True] * 30, metrics={"y": pa.array(np.arange(30.0))})
    (panel,) = sweep_panels(table)
    assert panel.x_name == "seed"
    np.testing.assert_array_equal(panel.x, np.arange(100.0, 130.0))


def test_plot_is_a_real_png(tmp_path: Path) -> None:
    out = plot_sweep(linear_sweep(300, failed=20), tmp_path / "sweep.png")
    image = assert_real_png(out)
    # Four panels (y, z, success, ok) in rows of three: 3 across, 2 down.
    assert image.shape[1] == round(3 * PANEL_IN[0] * DPI)
    assert image.shape[0] > round(2 * PANEL_IN[1] * DPI)


@pytest.mark.parametrize("failed", [0, 12], ids=["no runs", "all failed"])
def test_a_sweep_without_ok_runs_still_gets_a_png(tmp_path: Path, failed: int) -> None:
    ok = np.zeros(failed, bool)
    table = results_table(ok, metrics={"y": pa.array(np.full(failed, np.nan), mask=~ok)})
    assert sweep_panels(table) == []
    assert_real_png(plot_sweep(table, tmp_path / "empty.png"))


def test_plot_refuses_a_path_that_is_not_png(tmp_path: Path) -> None:
    with pytest.raises(SweepError, match=r"ending in \.png"):
        plot_sweep(linear_sweep(20), tmp_path / "sweep.pdf")


# -- reading results and the command ----------------------------------------------------


@pytest.fixture()
def results_file(tmp_path: Path) -> Path:
    path = tmp_path / "results.parquet"
    pq.write_table(linear_sweep(200, failed=10), path)
    return path


def test_bad_results_files_are_refused_in_one_line(tmp_path: Path, results_file: Path) -> None:
    text = tmp_path / "notes.parquet"
    text.write_text("runs: 12\nall fine\n")
    cut = tmp_path / "cut.parquet"
    cut.write_bytes(results_file.read_bytes()[:2000])
    plain = tmp_path / "plain.parquet"
    pq.write_table(pa.table({"a": [1, 2, 3]}), plain)
    cases = {
        tmp_path / "missing.parquet": "not found",
        text: "not a Parquet file",
        cut: "not a Parquet file",
        plain: "is not an armfleet sweep's results",
    }
    for path, phrase in cases.items():
        with pytest.raises(SweepError) as caught:
            read_results(path)
        assert phrase in str(caught.value) and str(path) in str(caught.value)
    assert read_results(results_file).num_rows == 200


def test_run_prints_the_summary_and_writes_the_plot(
    results_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "figure.png"
    args = argparse.Namespace(results=str(results_file), plot=str(out), plot_against="x1")
    assert run_command(args) == 0
    printed = capsys.readouterr().out
    assert "200 runs, 190 ok, 10 failed" in printed
    assert printed.rstrip().splitlines()[-1] == f"plot: {out}"
    assert_real_png(out)


def test_command_line(results_file: Path) -> None:
    command = [sys.executable, "-m", "armfleet.cli.main", "sweep-report"]
    done = subprocess.run(
        [*command, str(results_file)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    default_plot = results_file.with_suffix(".png")
    assert done.stdout.rstrip().splitlines()[-1] == f"plot: {default_plot}"
    assert "success rate" in done.stdout
    assert_real_png(default_plot)

    refused = subprocess.run(
        [*command, str(results_file), "--plot-against", "x9"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert refused.returncode == 2
    assert refused.stdout == ""
    (line,) = refused.stderr.splitlines()
    assert line.startswith("armfleet: error: ") and "x1, x2" in line
