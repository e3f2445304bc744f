"""``armfleet.sweep(...)``: a scenario for N seeds on Ray, one Parquet row per run."""

from __future__ import annotations

import importlib.metadata
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import pyarrow as pa

from armfleet.checks.number_ranges import (
    SWEEP_BASE_SEED,
    SWEEP_BATCH,
    SWEEP_RUN_TIMEOUT_S,
    SWEEP_RUNS,
    SWEEP_WORKERS,
)
from armfleet.checks.user_paths import file_problem
from armfleet.sweeps.definition import SweepDefinition, load_sweep
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.output_path import results_path
from armfleet.sweeps.progress import SweepProgress
from armfleet.sweeps.ray_session import check_address, ray_session
from armfleet.sweeps.results_file import ResultsWriter, journal_path, read_results
from armfleet.sweeps.results_schema import SweepMetadata
from armfleet.sweeps.runner import RunCounts, SweepDriver

RUNS = SWEEP_RUNS
WORKERS = SWEEP_WORKERS
RUN_TIMEOUT_S = SWEEP_RUN_TIMEOUT_S
BASE_SEED = SWEEP_BASE_SEED
BATCH = SWEEP_BATCH


@dataclass(frozen=True)
class SweepResult:
    """What a sweep left.

    Attributes:
        table: every row of the results file (earlier rows of a resumed sweep included).
        path: the results file (None when the caller gave no ``output``).
        counts: what this call ran (finished, failed, wall time).
        definition: the sweep.
        interrupted: it was stopped by Ctrl-C before every run finished.
    """

    table: pa.Table
    path: Path | None
    counts: RunCounts
    definition: SweepDefinition
    interrupted: bool = False


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped the sweep; :attr:`result` holds the rows kept (the file is whole)."""

    def __init__(self, result: SweepResult) -> None:
        super().__init__("sweep interrupted")
        self.result = result


def sweep(
    scenario: str | Path,
    *,
    runs: int | None = None,
    address: str | None = None,
    workers: int | None = None,
    output: str | Path | None = None,
    resume: bool = False,
    overwrite: bool = False,
    run_timeout_s: float | None = None,
    base_seed: int | None = None,
    batch_size: int | None = None,
    progress: bool = True,
) -> SweepResult:
    """Run ``scenario`` for ``runs`` seeds (``base_seed + i``) on Ray.

    Everything is checked before Ray starts; then a private local Ray instance (or the
    cluster at ``address``) runs the batches, and the rows go to ``output`` as they come.

    Args:
        scenario: a shipped scenario (``handover``, ``reach``, ...), a launch spec with a
            ``sweep:`` section, or a sweep file.
        runs: how many runs; default: the sweep's ``runs``.
        address: None for a private local instance; ``"auto"``, ``"ray://HOST:PORT"``
            or ``"HOST:PORT"`` to join a running cluster.
        workers: runs at once; default: every core of the local machine (or CPU of the
            cluster).
        output: the Parquet file; None keeps the rows in :attr:`SweepResult.table` only.
        resume: run only the seeds ``output`` does not hold yet.
        overwrite: replace an existing ``output`` (otherwise refused, unless resuming).
        run_timeout_s: a run past it fails; default: the sweep's ``run_timeout_s``.
        base_seed: default: the sweep's ``base_seed``.
        batch_size: runs per Ray task; default: sized from the runs seen (~2 s per task).
        progress: show the progress bar on stderr.

    Raises:
        SweepError, SpecError: bad input, before anything starts.
        SweepInterrupted: Ctrl-C; the results file holds every finished run.
    """
    definition = _configured(load_sweep(scenario), runs, run_timeout_s, base_seed)
    count = definition.runs
    if count is None:
        raise SweepError(f"{scenario}: give the number of runs (--runs N); its sweep sets none")
    if workers is not None:
        workers = int(WORKERS.check(workers, "workers"))
    if batch_size is not None:
        batch_size = int(BATCH.check(batch_size, "batch_size"))
    if address is not None:
        check_address(address)
    temporary = None
    if output is None:
        temporary = tempfile.TemporaryDirectory(prefix="armfleet-sweep-")
        path = Path(temporary.name) / "results.parquet"
    else:
        path = results_path(output, resume, overwrite)
    try:
        kept = _kept_rows(path, definition) if resume else None
        done = set() if kept is None else {int(s) for s in kept.column("seed").to_pylist()}
        seeds = [
            s for s in range(definition.base_seed, definition.base_seed + count) if s not in done
        ]
        metadata = _metadata(definition, count) if kept is None else _resumed(kept, count)
        integers = frozenset(
            column
            for parameter in definition.randomization
            if parameter.distribution.is_integer and parameter.distribution.size == 0
            for column in parameter.columns
        )
        counts, interrupted = RunCounts(), False
        if seeds:
            counts, interrupted = _run(
                definition,
                seeds,
                path,
                metadata,
                integers,
                kept,
                address,
                workers,
                batch_size,
                progress,
            )
        elif kept is None:
            ResultsWriter(path, metadata, integers).close()
        table = read_results(path)
        result = SweepResult(table, None if temporary else path, counts, definition, interrupted)
    finally:
        if temporary is not None:
            temporary.cleanup()
    if interrupted:
        raise SweepInterrupted(result)
    return result


def _run(
    definition: SweepDefinition,
    seeds: list[int],
    path: Path,
    metadata: SweepMetadata,
    integers: frozenset[str],
    kept: pa.Table | None,
    address: str | None,
    workers: int | None,
    batch_size: int | None,
    show: bool,
) -> tuple[RunCounts, bool]:
    if show:  # Ray takes seconds to start: say so before the bar appears
        where = (
            "a private local Ray instance" if address is None else f"the Ray cluster at {address}"
        )
        print(f"sweep: {len(seeds)} runs; starting {where}...", file=sys.stderr, flush=True)
    with ray_session(address, workers) as session:
        writer = ResultsWriter(path, metadata, integers, kept)
        progress = SweepProgress(len(seeds), 0 if kept is None else kept.num_rows, show)
        driver = SweepDriver(session, definition, writer, progress, batch_size)
        interrupted = False
        try:
            driver.run(seeds)
        except KeyboardInterrupt:
            interrupted = True
        except Exception as exc:  # the driver's own failure: one line, the rows kept
            kept_runs = driver.counts.finished + (0 if kept is None else kept.num_rows)
            raise SweepError(
                f"the sweep stopped: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}; "
                f"{path} keeps its {kept_runs} finished runs (--resume runs the rest)"
            ) from exc
        finally:
            progress.close()
            writer.close()
    return driver.counts, interrupted


def _configured(
    definition: SweepDefinition,
    runs: int | None,
    run_timeout_s: float | None,
    base_seed: int | None,
) -> SweepDefinition:
    changes: dict[str, object] = {}
    if runs is not None:
        changes["runs"] = int(RUNS.check(runs, "runs"))
    if run_timeout_s is not None:
        changes["run_timeout_s"] = RUN_TIMEOUT_S.check(run_timeout_s, "run_timeout_s")
    if base_seed is not None:
        changes["base_seed"] = int(BASE_SEED.check(base_seed, "base_seed"))
    return replace(definition, **changes)  # type: ignore[arg-type]


def _kept_rows(path: Path, definition: SweepDefinition) -> pa.Table | None:
    if file_problem(path) == "not found" and file_problem(journal_path(path)) is not None:
        return None  # nothing to resume: a fresh sweep
    table = read_results(path)
    metadata = SweepMetadata.from_schema(table.schema)
    assert metadata is not None  # read_results checked it
    theirs = (metadata.task, metadata.base_seed, metadata.parameters, metadata.digest)
    ours = (
        definition.task.name,
        definition.base_seed,
        definition.parameter_columns,
        definition.digest,
    )
    if theirs != ours:
        raise SweepError(
            f"{path} holds another sweep (task {metadata.task}, base seed {metadata.base_seed}, "
            f"{len(metadata.parameters)} parameter columns, or a spec, parameters or "
            "randomization changed since); resume it with the same sweep, or give another -o"
        )
    return table


def _metadata(definition: SweepDefinition, runs: int) -> SweepMetadata:
    return SweepMetadata(
        scenario=definition.scenario,
        spec=definition.spec.source,
        task=definition.task.name,
        base_seed=definition.base_seed,
        runs=runs,
        parameters=definition.parameter_columns,
        armfleet=importlib.metadata.version("armfleet"),
        digest=definition.digest,
    )


def _resumed(kept: pa.Table, runs: int) -> SweepMetadata:
    metadata = SweepMetadata.from_schema(kept.schema)
    assert metadata is not None
    return replace(metadata, runs=max(runs, metadata.runs))
