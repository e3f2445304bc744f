"""``armfleet sweep SCENARIO --runs N``: a scenario for N seeds on Ray, rows to Parquet."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from armfleet.checks.number_ranges import (
    SWEEP_BASE_SEED,
    SWEEP_BATCH,
    SWEEP_RUN_TIMEOUT_S,
    SWEEP_RUNS,
    SWEEP_WORKERS,
)
from armfleet.cli.number_arguments import integer_in, number_in
from armfleet.cli.parser import OneLineParser
from armfleet.cli.path_arguments import path_text

if TYPE_CHECKING:
    from armfleet.sweeps.sweep import SweepResult


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "sweep",
        help="run a scenario for many seeds on Ray (one Parquet row per run)",
        description="Run SCENARIO for N seeds (base_seed + i), each in a world of its own, "
        "on a private local Ray instance (every core) or a cluster (--address). Rows go to "
        "the results file as runs finish; Ctrl-C keeps them, --resume runs the rest. At the "
        "end: a summary table and a plot. SCENARIO is a shipped scenario (see the error for "
        "the list), a launch spec with a sweep: section, or a sweep file (docs/sweeps.md).",
    )
    parser.add_argument("scenario", type=path_text, metavar="SCENARIO", help="the scenario")
    parser.add_argument(
        "--runs", type=integer_in(SWEEP_RUNS), default=None, metavar="N",
        help="runs (default: the sweep's runs:)",
    )  # fmt: skip
    parser.add_argument(
        "--address", default=None, metavar="ray://HOST:PORT|auto",
        help="join this Ray cluster instead of starting a private local instance",
    )  # fmt: skip
    parser.add_argument(
        "--workers", type=integer_in(SWEEP_WORKERS), default=None, metavar="K",
        help="runs at once (default: every core, or the cluster's CPUs)",
    )  # fmt: skip
    parser.add_argument(
        "-o", "--output", type=path_text, default=None, metavar="RESULTS.parquet",
        help="results file (default: sweep-<scenario>.parquet here)",
    )  # fmt: skip
    parser.add_argument(
        "--resume", action="store_true", help="run only the seeds the results file lacks"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace the results file")
    parser.add_argument(
        "--run-timeout", type=number_in(SWEEP_RUN_TIMEOUT_S), default=None, metavar="S",
        help="a run past S seconds fails (default: the sweep's run_timeout_s, else 600)",
    )  # fmt: skip
    parser.add_argument(
        "--base-seed", type=integer_in(SWEEP_BASE_SEED), default=None, metavar="SEED",
        help="run i has seed SEED + i (default: the sweep's base_seed, else 0)",
    )  # fmt: skip
    parser.add_argument(
        "--batch-size", type=integer_in(SWEEP_BATCH), default=None, metavar="B",
        help="runs per Ray task (default: sized to about 2 s of work)",
    )  # fmt: skip
    parser.add_argument(
        "--plot-against", default=None, metavar="PARAM",
        help="the parameter column on the plot's x axis (default: the one that explains "
        "each metric most)",
    )  # fmt: skip
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    # Ray and pyarrow load only for this command (and say which extra they need).
    from armfleet.sweeps.definition import load_sweep
    from armfleet.sweeps.errors import SweepError
    from armfleet.sweeps.sweep import SweepInterrupted, sweep

    if args.plot_against is not None:  # refused before anything starts, not after the runs
        columns = load_sweep(args.scenario).parameter_columns
        if args.plot_against not in columns:
            raise SweepError(
                f"--plot-against {args.plot_against!r}: not a parameter of this sweep; "
                f"its parameters: {', '.join(columns) or 'none'}"
            )
    output = args.output
    if output is None:
        output = f"sweep-{Path(args.scenario).stem}.parquet"
    began = time.perf_counter()
    # A polite kill (SIGTERM: a job scheduler's, a closed session's) stops it as Ctrl-C
    # does: the results file is closed properly, with every finished run.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        result = sweep(
            args.scenario,
            runs=args.runs,
            address=args.address,
            workers=args.workers,
            output=output,
            resume=args.resume,
            overwrite=args.overwrite,
            run_timeout_s=args.run_timeout,
            base_seed=args.base_seed,
            batch_size=args.batch_size,
            progress=not args.quiet,
        )
    except SweepInterrupted as stop:
        kept, asked = stop.result.table.num_rows, stop.result.definition.runs
        print(
            f"interrupted: {kept} of {asked} runs kept in {output}; add --resume to run the rest",
            file=sys.stderr,
        )
        return 130
    finally:
        signal.signal(signal.SIGTERM, previous)
    _report(result, time.perf_counter() - began, args.plot_against)
    return 0


def _interrupt(signum: int, frame: FrameType | None) -> None:
    del signum, frame
    raise KeyboardInterrupt


def _report(result: SweepResult, seconds: float, plot_against: str | None) -> None:
    from armfleet.sweeps.report_plot import plot_sweep
    from armfleet.sweeps.summary import summarize

    counts = result.counts
    rate = counts.finished / counts.wall_s if counts.wall_s else 0.0
    print(summarize(result.table).format())
    print(
        f"ran {counts.finished} runs ({counts.failed} failed) in {counts.wall_s:.1f} s, "
        f"{rate:.2f} runs/s; {seconds:.1f} s in all"
    )
    assert result.path is not None
    print(f"results: {result.path} ({result.table.num_rows} rows)")
    plot = plot_sweep(result.table, result.path.with_suffix(".png"), plot_against)
    print(f"plot: {plot}")
