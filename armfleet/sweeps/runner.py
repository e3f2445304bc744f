"""Run a sweep on Ray: batches of runs to the workers, rows to the results as they return.

The driver keeps one batch in flight per worker (plus one queued, so no worker waits),
sizes the batches from the runs seen so far (about :data:`TASK_TARGET_S` of work each),
and writes each batch's rows as soon as it returns. Faults stay in their runs:

- a task that raises or runs past its time limit is a failed row (inside the worker);
- a worker process that dies (``kill -9``, out of memory) costs only its batch in
  flight: Ray runs the batch again (:data:`MAX_RETRIES`), and its rows appear once;
- a batch that does not return long after its runs' time limits (a run stuck in C code
  that the in-process limit cannot interrupt) gets its worker killed; its runs are
  then tried one per task, and the one that hangs again becomes a failed row.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from armfleet.sweeps.batch import run_batch
from armfleet.sweeps.definition import SweepDefinition
from armfleet.sweeps.progress import SweepProgress
from armfleet.sweeps.ray_session import RaySession
from armfleet.sweeps.results_file import ResultsWriter
from armfleet.sweeps.results_schema import RUN_COLUMNS
from armfleet.sweeps.run import Row
from armfleet.sweeps.run_timeout import TIMED_OUT

#: Work per Ray task the batch size aims at [s].
TASK_TARGET_S = 2.0
MAX_BATCH = 64
#: Times Ray runs a batch again after its worker died.
MAX_RETRIES = 2
#: Grace beyond (twice) a batch's time limits before the driver kills its worker [s].
BACKSTOP_GRACE_S = 30.0


@dataclass
class _Batch:
    seeds: tuple[int, ...]
    submitted: float
    deadline: float
    alone: bool  # one run, tried alone after its batch was killed


@dataclass
class RunCounts:
    """What the driver saw.

    Attributes:
        finished: runs whose rows were written.
        failed: of those, the failed ones.
        retried_batches: batches whose worker was killed by the backstop.
        wall_s: the driver's wall time from the first submission [s].
        driver_s: of that, the time spent taking batches' rows and writing them [s]
            (what bounds a driver's rate on a large cluster).
        batches: batches whose rows came back.
    """

    finished: int = 0
    failed: int = 0
    retried_batches: int = 0
    wall_s: float = 0.0
    driver_s: float = 0.0
    batches: int = 0
    run_wall_s: list[float] = field(default_factory=list)


class SweepDriver:
    """Runs ``seeds`` of ``definition`` on ``session``, writing rows to ``writer``."""

    def __init__(
        self,
        session: RaySession,
        definition: SweepDefinition,
        writer: ResultsWriter,
        progress: SweepProgress,
        batch_size: int | None = None,
    ) -> None:
        self._ray = session.ray
        self._workers = session.workers
        self._definition = definition
        self._writer = writer
        self._progress = progress
        self._fixed_batch = batch_size
        self._remote = self._ray.remote(num_cpus=1, max_retries=MAX_RETRIES)(run_batch)
        self._definition_ref = self._ray.put(definition)
        self._in_flight: dict[Any, _Batch] = {}
        self.counts = RunCounts()

    def run(self, seeds: Iterable[int]) -> RunCounts:
        """Run every seed; on KeyboardInterrupt, drop what is in flight and re-raise (the
        rows written so far stay written).

        The batches in flight are not cancelled: they end with the Ray job when the sweep's
        session shuts down, as every task of a job does. Force-cancelling them as they
        finished tripped Ray 2.60's own check ("Tried to complete task that was not
        pending") and aborted the sweep with Ray's stack trace instead of exit 130 (once
        in four clean CI runs)."""
        pending = deque(seeds)
        began = time.perf_counter()
        try:
            while pending or self._in_flight:
                while pending and len(self._in_flight) < self._workers + 1:
                    self._submit(pending)
                ready, _ = self._ray.wait(list(self._in_flight), num_returns=1, timeout=0.5)
                for ref in ready:
                    self._collect(ref)
                self._enforce_deadlines(pending)
        except BaseException:
            self._in_flight.clear()
            raise
        finally:
            self.counts.wall_s = time.perf_counter() - began
        return self.counts

    def _batch_size(self, remaining: int) -> int:
        if self._fixed_batch is not None:
            return self._fixed_batch
        walls = self.counts.run_wall_s
        if not walls:
            return 1  # nothing measured yet: one run per worker first
        mean = sum(walls) / len(walls)
        wanted = max(1, min(MAX_BATCH, math.floor(TASK_TARGET_S / max(mean, 1e-6))))
        fair = max(1, math.ceil(remaining / self._workers))  # no worker left with the tail
        return min(wanted, fair)

    def _submit(self, pending: deque[int], alone: bool = False) -> None:
        size = 1 if alone else self._batch_size(len(pending))
        seeds = tuple(pending.popleft() for _ in range(min(size, len(pending))))
        now = time.perf_counter()
        # A run may take its bring-up's limit and its task's; twice that for the batch, as a
        # queued batch may first wait for a worker's last batch.
        run_limit_s = 2 * self._definition.run_timeout_s + 10.0
        limit = 2 * len(seeds) * run_limit_s + BACKSTOP_GRACE_S
        ref = self._remote.remote(self._definition_ref, seeds)
        self._in_flight[ref] = _Batch(seeds, now, now + limit, alone)

    def _collect(self, ref: Any) -> None:
        began = time.perf_counter()
        batch = self._in_flight.pop(ref)
        try:
            rows: list[Row] = self._ray.get(ref)
        except self._ray.exceptions.TaskCancelledError:
            return
        except Exception as exc:  # the worker died more often than Ray retries it
            exc = getattr(exc, "cause", None) or exc  # a RayTaskError's own exception
            message = " ".join(str(exc).split())[:500]
            rows = [
                failed_row(self._definition, seed, f"{type(exc).__name__}: {message}")
                for seed in batch.seeds
            ]
        self._write(rows)
        self.counts.batches += 1
        self.counts.driver_s += time.perf_counter() - began

    def _write(self, rows: list[Row]) -> None:
        self._writer.append(rows)
        failed = sum(not row["ok"] for row in rows)
        self.counts.finished += len(rows)
        self.counts.failed += failed
        self.counts.run_wall_s.extend(row["wall_s"] for row in rows if row["wall_s"])
        self._progress.update(len(rows), failed)

    def _enforce_deadlines(self, pending: deque[int]) -> None:
        now = time.perf_counter()
        for ref, batch in list(self._in_flight.items()):
            if now < batch.deadline:
                continue
            self._ray.cancel(ref, force=True)
            del self._in_flight[ref]
            self.counts.retried_batches += 1
            if batch.alone:
                waited = now - batch.submitted
                self._write(
                    [
                        failed_row(
                            self._definition,
                            batch.seeds[0],
                            f"{TIMED_OUT}: the worker did not return within {waited:.0f} s "
                            "(a run stuck where its time limit cannot interrupt it); "
                            "it was killed",
                        )
                    ]
                )
                continue
            for seed in reversed(batch.seeds):  # each alone, next
                pending.appendleft(seed)
            for _ in batch.seeds:
                self._submit(pending, alone=True)


def failed_row(definition: SweepDefinition, seed: int, error: str) -> Row:
    """The row of a run that returned none of its own: its drawn parameters and ``error``."""
    row: Row = {name: None for name in RUN_COLUMNS}
    row.update(seed=seed, ok=False, error=error, metrics={})
    for parameter in definition.randomization:
        try:
            row.update(parameter.row(parameter.draw(seed)))
        except Exception:  # a draw that fails leaves its columns empty
            continue
    return row
