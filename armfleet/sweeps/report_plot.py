"""A figure of a sweep's results: each metric against the parameter that explains it most.

One panel per numeric or bool metric (text metrics are left out), plus one of ``ok`` when
some runs failed. A panel's x axis is the parameter given, or else the one with the largest
correlation ratio eta^2 (:func:`explained_variance`) for that metric, named with its eta^2
in the panel's title; with no parameters, the run's seed. Numeric metrics show the ok runs
as points and the mean of each bin of the parameter as a line; bool metrics show each
bin's rate with its 95 % Wilson interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
import pyarrow as pa

from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.summary import (
    ResultsColumns,
    column_flags,
    column_floats,
    results_columns,
    success_flags,
    wilson_interval,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Quantile bins of a parameter (fewer when its quantiles coincide or it has fewer values).
BINS = 10
#: Resolution of the figure [dots per inch].
DPI = 100
#: Size of one panel [in].
PANEL_IN = (4.6, 3.4)
#: Panels per row, at most.
COLUMNS = 3
POINT_COLOR = "#4c72b0"
MEAN_COLOR = "#dd8452"


class PanelKind(Enum):
    """How a metric is drawn."""

    NUMERIC = "numeric"  # points of the ok runs and the bins' means
    RATE = "rate"  # each bin's rate of true with its Wilson interval


@dataclass(frozen=True, eq=False)  # arrays have no single truth of equality
class Panel:
    """One metric against one parameter, over the rows that have both.

    Attributes:
        metric: the metric's column (or ``ok``).
        kind: how it is drawn.
        x_name: the parameter on the x axis (or ``seed``).
        eta2: the share of the metric's variance the parameter's bins explain, in [0, 1].
        x: the parameter's values.
        y: the metric's values (0.0 or 1.0 for a bool).
    """

    metric: str
    kind: PanelKind
    x_name: str
    eta2: float
    x: npt.NDArray[np.float64]
    y: npt.NDArray[np.float64]


def bin_groups(x: npt.NDArray[np.float64], bins: int = BINS) -> npt.NDArray[np.intp]:
    """The bin of each value of ``x``, numbered in increasing ``x`` from 0.

    A parameter with at most ``bins`` distinct values has one bin per value; otherwise
    the bins are its quantiles, those with identical edges merged into one.
    """
    distinct, inverse = np.unique(x, return_inverse=True)
    if distinct.size <= bins:
        return np.asarray(inverse, dtype=np.intp).reshape(x.shape)
    edges = np.unique(np.quantile(x, np.linspace(0.0, 1.0, bins + 1)))
    return np.asarray(np.searchsorted(edges[1:-1], x, side="right"), dtype=np.intp)


def explained_variance(x: npt.ArrayLike, y: npt.ArrayLike, bins: int = BINS) -> float:
    """The correlation ratio eta^2 of ``y`` on ``x``: the share of ``y``'s variance that
    the means of ``y`` in the quantile bins of ``x`` (:func:`bin_groups`) explain.

    Args:
        x: the parameter, one value per run.
        y: the metric, one value per run (a bool as 0 or 1); pairs where either is not
            finite are left out.
        bins: quantile bins of ``x``.

    Returns:
        eta^2 in [0, 1]: 1 when ``y`` is constant within each bin, near 0 when the bins'
        means agree; 0.0 when ``y`` does not vary (nothing to explain) or there are fewer
        than two pairs. Pure noise over ``n`` runs gives about ``(bins - 1) / n``.
    """
    xs = np.asarray(x, dtype=np.float64)
    ys = np.asarray(y, dtype=np.float64)
    kept = np.isfinite(xs) & np.isfinite(ys)
    xs, ys = xs[kept], ys[kept]
    if ys.size < 2:
        return 0.0
    deviation = ys - ys.mean()
    total = float(np.dot(deviation, deviation))
    if total <= 0.0:
        return 0.0
    groups = bin_groups(xs, bins)
    counts = np.bincount(groups)
    sums = np.bincount(groups, weights=deviation)
    present = counts > 0
    between = float(np.sum(sums[present] ** 2 / counts[present]))
    return min(1.0, between / total)


def plot_sweep(table: pa.Table, out: Path, plot_against: str | None = None) -> Path:
    """Write the figure of a sweep's results to ``out`` as a PNG.

    Args:
        table: the sweep's results, one row per run (see :mod:`armfleet.sweeps.results_schema`).
        out: the PNG to write (its folder must exist; a file there is replaced).
        plot_against: the parameter column on every panel's x axis; None picks, per metric,
            the parameter of largest eta^2 (the seed if the sweep has no parameters).

    Returns:
        ``out``. A table without ok runs or without numeric or bool metrics still gets a
        figure, saying so in words.

    Raises:
        SweepError: the table is not a sweep's results, ``plot_against`` is no parameter
            column (the message lists them), ``out`` does not end in ``.png`` or cannot be
            written.
    """
    out = Path(out)
    if out.suffix.lower() != ".png":
        raise SweepError(f"the plot is a PNG: give a path ending in .png (got {str(out)!r})")
    panels = sweep_panels(table, plot_against)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    ok = int(column_flags(table, "ok").sum())
    title = _escaped(
        f"sweep of {results_columns(table).metadata.scenario}: {table.num_rows} runs, "
        f"{ok} ok, {table.num_rows - ok} failed"
    )
    if panels:
        figure = _panel_figure(panels, title)
    elif table.num_rows == 0:
        figure = _text_figure(title, "no runs to plot")
    elif ok == 0:
        figure = _text_figure(title, "no ok runs to plot: every run failed")
    else:
        figure = _text_figure(title, "no numeric or bool metrics to plot")
    FigureCanvasAgg(figure)
    try:
        figure.savefig(out, dpi=DPI, format="png")
    except OSError as exc:
        raise SweepError(f"cannot write the plot {out}: {exc.strerror or exc}") from None
    return out


def sweep_panels(table: pa.Table, plot_against: str | None = None) -> list[Panel]:
    """The panels of :func:`plot_sweep`, one per numeric or bool metric, then ``ok`` if
    some runs failed; none if no run is ok.

    A numeric metric's panel holds the ok runs that have a value; a bool metric's the runs
    that have one (failed runs have none), but ``success`` and ``ok`` count every run, a
    failed one as false. Its x axis is ``plot_against``, or else the parameter of largest
    eta^2 for that metric (the first of equals; the seed when there are no parameters).

    Raises:
        SweepError: the table is not a sweep's results, or ``plot_against`` is no
            parameter column (the message lists them).
    """
    columns = results_columns(table)
    candidates = _x_candidates(table, columns, plot_against)
    ok = column_flags(table, "ok")
    if not ok.any():
        return []
    metrics: list[tuple[str, PanelKind, npt.NDArray[np.float64]]] = []
    for name in columns.numeric:
        values = column_floats(table, name)
        metrics.append((name, PanelKind.NUMERIC, np.where(ok, values, np.nan)))
    for name in columns.flags:
        if name == columns.success_metric:  # a failed run is not successful
            values = success_flags(table, columns).astype(np.float64)
        else:
            values = np.where(ok, column_floats(table, name), np.nan)
        metrics.append((name, PanelKind.RATE, values))
    if not ok.all():
        metrics.append(("ok", PanelKind.RATE, ok.astype(np.float64)))
    xs = {name: column_floats(table, name) for name in candidates}
    panels = []
    for metric, kind, y in metrics:
        scored = [(explained_variance(xs[name], y), name) for name in candidates]
        eta2, best = max(scored, key=lambda pair: pair[0])  # max keeps the first of equals
        kept = np.isfinite(xs[best]) & np.isfinite(y)
        panels.append(Panel(metric, kind, best, eta2, xs[best][kept], y[kept]))
    return panels


def _x_candidates(
    table: pa.Table, columns: ResultsColumns, plot_against: str | None
) -> tuple[str, ...]:
    """The columns a panel's x axis may be, the best of them chosen per metric."""
    numeric = tuple(
        name for name in columns.parameters if _is_number(table.schema.field(name).type)
    )
    if plot_against is not None:
        if plot_against not in numeric:
            valid = ", ".join(numeric) if numeric else "(none: the sweep draws no parameters)"
            raise SweepError(
                f"cannot plot against {plot_against!r}: not a parameter of this sweep; "
                f"parameters: {valid}"
            )
        return (plot_against,)
    return numeric or ("seed",)


def _is_number(kind: pa.DataType) -> bool:
    return bool(pa.types.is_integer(kind) or pa.types.is_floating(kind))


def _panel_figure(panels: list[Panel], title: str) -> Figure:
    from matplotlib.figure import Figure

    ncols = min(COLUMNS, len(panels))
    nrows = math.ceil(len(panels) / ncols)
    width, height = PANEL_IN
    figure = Figure(figsize=(width * ncols, height * nrows + 0.4), dpi=DPI, layout="constrained")
    axes = figure.subplots(nrows, ncols, squeeze=False)
    for ax, panel in zip(axes.flat, panels, strict=False):
        _draw(ax, panel)
    for ax in axes.flat[len(panels) :]:
        ax.set_axis_off()
    figure.suptitle(title, fontsize=11)
    return figure


def _draw(ax: Axes, panel: Panel) -> None:
    metric, x_name = _escaped(panel.metric), _escaped(panel.x_name)
    ax.set_title(f"{metric}\nvs {x_name} ($\\eta^2$ = {panel.eta2:.2f})", fontsize=9)
    ax.set_xlabel(x_name, fontsize=8)
    ax.set_ylabel(metric if panel.kind is PanelKind.NUMERIC else f"rate of {metric}", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(True, lw=0.3, alpha=0.6)
    if panel.x.size == 0:
        ax.text(0.5, 0.5, "no values", ha="center", va="center", transform=ax.transAxes)
        return
    groups = bin_groups(panel.x)
    counts = np.bincount(groups)
    present = counts > 0
    centers = (np.bincount(groups, weights=panel.x)[present]) / counts[present]
    if panel.kind is PanelKind.NUMERIC:
        means = np.bincount(groups, weights=panel.y)[present] / counts[present]
        ax.scatter(panel.x, panel.y, s=6, alpha=0.35, color=POINT_COLOR, lw=0, label="ok runs")
        ax.plot(centers, means, color=MEAN_COLOR, marker="o", ms=3, lw=1.5, label="bin mean")
        ax.legend(loc="best", fontsize=7)
        return
    trues = np.bincount(groups, weights=panel.y)[present].round().astype(int)
    ns = counts[present]
    rates = trues / ns
    intervals = np.array([wilson_interval(int(k), int(n)) for k, n in zip(trues, ns, strict=True)])
    errors = np.clip(np.vstack([rates - intervals[:, 0], intervals[:, 1] - rates]), 0.0, None)
    ax.errorbar(
        centers, rates, yerr=errors, color=MEAN_COLOR, marker="o", ms=3, lw=1.2, capsize=3,
        label="bin rate, 95 % Wilson",
    )  # fmt: skip
    ax.set_ylim(-0.05, 1.05)
    ax.legend(loc="best", fontsize=7)


def _text_figure(title: str, text: str) -> Figure:
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6.4, 2.4), dpi=DPI)
    figure.suptitle(title, fontsize=11)
    figure.text(0.5, 0.45, text, ha="center", va="center", fontsize=12)
    return figure


def _escaped(text: str) -> str:
    """``text`` shown as is: a ``$`` in a column's name would start matplotlib's math."""
    return text.replace("$", r"\$")
