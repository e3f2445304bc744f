"""``armfleet sweep-report RESULTS.parquet [--plot-against PARAM] [--plot OUT.png]``: the
summary table of a sweep's results and a figure of its metrics against its parameters."""

from __future__ import annotations

import argparse
from pathlib import Path

from armfleet.cli.parser import OneLineParser
from armfleet.cli.path_arguments import path_text


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "sweep-report",
        help="summarize a sweep's results and plot its metrics against its parameters",
        description="Print the runs, failures, success rate (95 % Wilson interval) and each "
        "metric's median, 5th and 95th percentiles of a sweep's results, and write a figure "
        "of each metric against the parameter that explains it most (or the one given).",
    )
    parser.add_argument(
        "results", type=path_text, metavar="RESULTS.parquet", help="the sweep's results"
    )
    parser.add_argument(
        "--plot-against", default=None, metavar="PARAM",
        help="the parameter column on every panel's x axis (default: per metric, the one "
        "explaining most of its variance)",
    )  # fmt: skip
    parser.add_argument(
        "--plot", type=path_text, default=None, metavar="OUT.png",
        help="the figure to write (default: RESULTS with the suffix .png)",
    )  # fmt: skip
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    # pyarrow and matplotlib load only for this command (the sweeps extra).
    from armfleet.sweeps.report_plot import plot_sweep
    from armfleet.sweeps.results_file import read_results
    from armfleet.sweeps.summary import summarize

    results = Path(args.results)
    table = read_results(results)
    out = Path(args.plot) if args.plot is not None else results.with_suffix(".png")
    summary = summarize(table)
    plot_sweep(table, out, args.plot_against)
    print(summary.format())
    print(f"plot: {out}")
    return 0
