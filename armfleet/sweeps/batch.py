"""The unit of work sent to a Ray worker: several runs, one after the other.

Batching keeps Ray's cost per task (about 1 ms to schedule and return) small against
the runs; each run still has a world of its own, made and closed inside the batch.
"""

from __future__ import annotations

from collections.abc import Sequence

from armfleet.description import ModelLibrary
from armfleet.sweeps.definition import SweepDefinition
from armfleet.sweeps.run import Row, run_seed


def run_batch(definition: SweepDefinition, seeds: Sequence[int]) -> list[Row]:
    """The rows of the runs of ``seeds``, in order; a failed run is a row too."""
    task = None
    try:
        task = definition.task.load()
    except Exception:  # each run then reports why the task cannot be loaded
        task = None
    models = ModelLibrary()  # each model's description read once for the whole batch
    return [run_seed(definition, seed, task, models) for seed in seeds]
