"""What a sweep's results say, in numbers: runs, failures, the success rate and each metric.

:func:`summarize` reads a results table (see :mod:`armfleet.sweeps.results_schema`) into a
:class:`SweepSummary`, whose :meth:`~SweepSummary.format` is the plain-text table
``armfleet sweep-report`` prints. Rates carry a 95 % Wilson score interval
(:func:`wilson_interval`); numeric metrics their median, 5th and 95th percentiles.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import pyarrow.compute as pc

from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.results_schema import RUN_COLUMNS, SweepMetadata
from armfleet.sweeps.run_timeout import TIMED_OUT

#: The standard normal quantile of 97.5 %: a two-sided 95 % interval.
Z_95 = 1.959963984540054
#: The bool metric that, when the task returns one, is a run's success (else ``ok`` is).
SUCCESS_METRIC = "success"
#: How many of the most common error messages the summary lists.
COMMON_ERRORS = 3
#: An error message longer than this is cut in the table [characters].
ERROR_CHARS = 100


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion.

    Args:
        successes: trials that succeeded, ``0 <= successes <= n``.
        n: trials.
        z: the normal quantile of the interval (:data:`Z_95` for 95 %).

    Returns:
        ``(low, high)`` within [0, 1]; ``(0.0, 1.0)`` for no trials (nothing is known).
    """
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    denominator = 1.0 + z * z / n
    center = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denominator
    return max(0.0, center - half), min(1.0, center + half)


@dataclass(frozen=True)
class Rate:
    """A proportion with its 95 % Wilson score interval.

    Attributes:
        name: what is counted (a bool metric, or ``ok``).
        successes: rows where it is true.
        n: rows counted.
        low: lower end of the interval.
        high: upper end of the interval.
    """

    name: str
    successes: int
    n: int
    low: float
    high: float

    @property
    def rate(self) -> float:
        """``successes / n``; NaN with no rows."""
        return self.successes / self.n if self.n else math.nan

    @classmethod
    def of(cls, name: str, successes: int, n: int) -> Rate:
        """The rate of ``successes`` in ``n`` with its Wilson interval."""
        low, high = wilson_interval(successes, n)
        return cls(name, successes, n, low, high)


@dataclass(frozen=True)
class Distribution:
    """Median and tails of a numeric metric over the rows that have a value.

    Attributes:
        name: the metric's column.
        n: rows with a value (not null, not NaN).
        median: the 50th percentile (NaN with no values), in the metric's unit.
        p5: the 5th percentile (linear interpolation, as :func:`numpy.percentile`).
        p95: the 95th percentile.
    """

    name: str
    n: int
    median: float
    p5: float
    p95: float

    @classmethod
    def of(cls, name: str, values: npt.NDArray[np.float64]) -> Distribution:
        """The distribution of ``values`` (NaN left out)."""
        kept = values[~np.isnan(values)]
        if kept.size == 0:
            return cls(name, 0, math.nan, math.nan, math.nan)
        p5, median, p95 = np.percentile(kept, [5.0, 50.0, 95.0])
        return cls(name, int(kept.size), float(median), float(p5), float(p95))


@dataclass(frozen=True)
class WallTimes:
    """Wall time per run, over every run that has it (failed runs included).

    Attributes:
        median_s: median of ``wall_s`` [s].
        p95_s: 95th percentile of ``wall_s`` [s].
        mean_bringup_s: mean of ``bringup_s`` [s].
        mean_task_s: mean of ``task_s`` [s].
        mean_stepping_s: mean of ``stepping_s`` [s].
    """

    median_s: float
    p95_s: float
    mean_bringup_s: float
    mean_task_s: float
    mean_stepping_s: float


@dataclass(frozen=True)
class ResultsColumns:
    """Which columns of a results table are parameters and which are metrics, by kind.

    Attributes:
        metadata: the sweep's metadata, from the table's schema.
        parameters: the parameter columns, in order.
        numeric: metrics of integer or float type.
        flags: metrics of bool type.
        text: metrics of any other type (strings), which are not summarized.
    """

    metadata: SweepMetadata
    parameters: tuple[str, ...]
    numeric: tuple[str, ...]
    flags: tuple[str, ...]
    text: tuple[str, ...]

    @property
    def success_metric(self) -> str | None:
        """:data:`SUCCESS_METRIC` if it is a bool metric, else None (``ok`` counts)."""
        return SUCCESS_METRIC if SUCCESS_METRIC in self.flags else None


def results_columns(table: pa.Table) -> ResultsColumns:
    """The parameters and the metrics of ``table``, sorted by kind.

    Raises:
        SweepError: the table holds no armfleet sweep metadata, or lacks a column its
            metadata or :data:`RUN_COLUMNS` names.
    """
    try:
        metadata = SweepMetadata.from_schema(table.schema)
    except (ValueError, TypeError) as exc:  # not JSON, or not the fields of a sweep
        raise SweepError(f"the results' sweep metadata cannot be read ({exc})") from None
    if metadata is None:
        raise SweepError("the table is not an armfleet sweep's results (no sweep metadata)")
    names = set(table.column_names)
    needed = (*RUN_COLUMNS, *metadata.parameters, *metadata.metrics)
    missing = [name for name in needed if name not in names]
    if missing:
        raise SweepError(f"the sweep's results lack the column(s): {', '.join(missing)}")
    numeric, flags, text = [], [], []
    for name in metadata.metrics:
        kind = table.schema.field(name).type
        if pa.types.is_boolean(kind):
            flags.append(name)
        elif pa.types.is_integer(kind) or pa.types.is_floating(kind):
            numeric.append(name)
        else:
            text.append(name)
    return ResultsColumns(metadata, metadata.parameters, tuple(numeric), tuple(flags), tuple(text))


def column_floats(table: pa.Table, name: str) -> npt.NDArray[np.float64]:
    """Column ``name`` of ``table`` as floats, NaN where it is null (bool: 0.0 or 1.0)."""
    floats = pc.cast(table.column(name), pa.float64())
    return np.asarray(floats.to_numpy(zero_copy_only=False), dtype=np.float64)


def column_flags(table: pa.Table, name: str) -> npt.NDArray[np.bool_]:
    """Bool column ``name`` of ``table`` with null read as False."""
    filled = pc.fill_null(table.column(name), False)
    return np.asarray(filled.to_numpy(zero_copy_only=False), dtype=np.bool_)


def success_flags(table: pa.Table, columns: ResultsColumns) -> npt.NDArray[np.bool_]:
    """Per row, whether the run succeeded: ``ok`` and (if there is one) the bool metric
    :data:`SUCCESS_METRIC`; a failed run is not successful."""
    ok = column_flags(table, "ok")
    if columns.success_metric is None:
        return ok
    return ok & column_flags(table, columns.success_metric)


@dataclass(frozen=True)
class SweepSummary:
    """The numbers of a sweep's results.

    Attributes:
        scenario: the sweep's scenario, as given.
        runs: rows in the results.
        ok_runs: runs whose task returned its metrics.
        failed_runs: the other runs.
        timed_out_runs: of the failed runs, those ended by their time limit
            (``run_timeout_s``, a limit of wall time: a loaded machine reaches it sooner).
        common_errors: the most common error messages of failed runs, with their counts,
            most common first (at most :data:`COMMON_ERRORS`).
        success: the success rate over every run (see :func:`success_flags`), named after
            what counted (``success`` or ``ok``).
        numeric: the distribution of each numeric metric over the ok runs that have it.
        rates: the rate of each bool metric other than ``success``, over the ok runs
            that have it.
        text: the metrics that are neither numbers nor bools, not summarized.
        wall: the wall times per run.
    """

    scenario: str
    runs: int
    ok_runs: int
    failed_runs: int
    timed_out_runs: int
    common_errors: tuple[tuple[str, int], ...]
    success: Rate
    numeric: tuple[Distribution, ...]
    rates: tuple[Rate, ...]
    text: tuple[str, ...]
    wall: WallTimes

    def format(self) -> str:
        """The summary as a plain-text table for the terminal (no trailing newline)."""
        lines = [
            f"sweep of {self.scenario}: {self.runs} runs, {self.ok_runs} ok, "
            f"{self.failed_runs} failed",
            f"ended by the time limit: {self.timed_out_runs} runs (run_timeout_s is wall time: "
            "a loaded machine reaches it sooner)",
        ]
        for i, (message, count) in enumerate(self.common_errors):
            label = "errors" if i == 0 else ""
            lines.append(f"  {label:<8}{count:>6}  {_cut(message)}")
        counted = (
            "a failed run counts as not successful"
            if self.success.name != "ok"
            else f"no bool metric {SUCCESS_METRIC!r}: runs ok"
        )
        lines.append(
            f"success rate {_rate(self.success)} (95 % Wilson; {self.success.name}: "
            f"{self.success.successes} of {self.success.n} runs; {counted})"
        )
        if self.numeric:
            width = max(len("metric"), *(len(d.name) for d in self.numeric))
            lines += ["", f"{'metric':<{width}}  {'n':>6}  {'median':>10}  {'p5':>10}  {'p95':>10}"]
            lines += [
                f"{d.name:<{width}}  {d.n:>6}  {_number(d.median):>10}  {_number(d.p5):>10}  "
                f"{_number(d.p95):>10}"
                for d in self.numeric
            ]
        if self.rates:
            width = max(len("bool metric"), *(len(r.name) for r in self.rates))
            lines += ["", f"{'bool metric':<{width}}  {'n':>6}  {'true':>6}  rate (95 % Wilson)"]
            lines += [
                f"{r.name:<{width}}  {r.n:>6}  {r.successes:>6}  {_rate(r)}" for r in self.rates
            ]
        if self.text:
            lines += ["", f"text metrics (not summarized): {', '.join(self.text)}"]
        wall = self.wall
        lines += [
            "",
            f"wall time per run [s]: median {_number(wall.median_s)}, p95 {_number(wall.p95_s)}; "
            f"mean bring-up {_number(wall.mean_bringup_s)}, task {_number(wall.mean_task_s)}, "
            f"stepping {_number(wall.mean_stepping_s)}",
        ]
        return "\n".join(lines)


def summarize(table: pa.Table) -> SweepSummary:
    """Summarize a sweep's results table.

    Args:
        table: one row per run, as written by a sweep (its schema holds the sweep's
            metadata); it may have no rows.

    Returns:
        The summary; values over no rows are NaN, rates over no rows have the interval
        [0, 1].

    Raises:
        SweepError: the table is not a sweep's results (see :func:`results_columns`).
    """
    columns = results_columns(table)
    ok = column_flags(table, "ok")
    success = success_flags(table, columns)
    errors = table.column("error").to_pylist()
    failed_errors = Counter(
        str(error) if error is not None else "(no message)"
        for error, row_ok in zip(errors, ok, strict=True)
        if not row_ok
    )
    rates = []
    for name in columns.flags:
        if name == columns.success_metric:
            continue
        values = column_floats(table, name)[ok]  # a failed run's metrics are not counted
        kept = values[~np.isnan(values)]
        rates.append(Rate.of(name, int(kept.sum()), int(kept.size)))
    return SweepSummary(
        scenario=columns.metadata.scenario,
        runs=table.num_rows,
        ok_runs=int(ok.sum()),
        failed_runs=int(table.num_rows - ok.sum()),
        timed_out_runs=sum(
            count for error, count in failed_errors.items() if error.startswith(TIMED_OUT)
        ),
        common_errors=tuple(failed_errors.most_common(COMMON_ERRORS)),
        success=Rate.of(columns.success_metric or "ok", int(success.sum()), table.num_rows),
        numeric=tuple(
            Distribution.of(name, column_floats(table, name)[ok]) for name in columns.numeric
        ),
        rates=tuple(rates),
        text=columns.text,
        wall=_wall_times(table),
    )


def _wall_times(table: pa.Table) -> WallTimes:
    wall = Distribution.of("wall_s", column_floats(table, "wall_s"))
    means = [_mean(column_floats(table, name)) for name in ("bringup_s", "task_s", "stepping_s")]
    return WallTimes(wall.median, wall.p95, *means)


def _mean(values: npt.NDArray[np.float64]) -> float:
    kept = values[~np.isnan(values)]
    return float(kept.mean()) if kept.size else math.nan


def _number(value: float) -> str:
    return "-" if math.isnan(value) else f"{value:.4g}"


def _rate(rate: Rate) -> str:
    if rate.n == 0:
        return "-"
    return f"{rate.rate:.3f} [{rate.low:.3f}, {rate.high:.3f}]"


def _cut(message: str) -> str:
    line = " ".join(message.split())  # a traceback's lines on one line
    return line if len(line) <= ERROR_CHARS else f"{line[: ERROR_CHARS - 3]}..."
