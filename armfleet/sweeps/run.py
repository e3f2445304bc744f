"""One run of a sweep: ``(definition, seed) -> row``, pure and self-contained.

The run draws its parameters, launches the spec headless in a world of its own, calls
the task with a generator seeded by the seed, closes the world, and returns its row.
Whatever the task does, the run returns a row: an exception, a time-out or metrics
that are not a flat mapping of numbers, bools and text become ``ok=False`` and an
``error``. The same seed gives the same parameters and metrics, bit for bit, in any
process and after any other runs (OMPL's random numbers are restarted from the seed).
"""

from __future__ import annotations

import os
import socket
import time
import traceback
from dataclasses import replace
from typing import Any

import numpy as np

from armfleet.description import ModelLibrary
from armfleet.planning.ompl_search import restart_random_numbers
from armfleet.sweeps.definition import SweepDefinition
from armfleet.sweeps.randomization import apply_draws
from armfleet.sweeps.results_schema import RUN_COLUMNS
from armfleet.sweeps.run_timeout import TIMED_OUT, RunTimedOut, RunTimeout
from armfleet.sweeps.task_reference import Task
from armfleet.world.launch import launch

#: Longest error text kept in a row [characters].
MAX_ERROR_CHARS = 2000

Row = dict[str, Any]
Metric = bool | int | float | str


def run_seed(
    definition: SweepDefinition,
    seed: int,
    task: Task | None = None,
    models: ModelLibrary | None = None,
) -> Row:
    """The row of the run of ``seed``: run columns, drawn parameters, and the task's
    metrics under ``"metrics"`` (a dict; empty when the run failed).

    Args:
        task: the loaded task (loaded from ``definition.task`` when None).
        models: the model library to launch from (a batch's runs share one: each
            model is read once per batch); a new one when None.
    """
    began = time.perf_counter()
    row: Row = {name: None for name in RUN_COLUMNS}
    row.update(seed=seed, ok=False, host=socket.gethostname(), pid=os.getpid(), metrics={})
    world = None
    bringup_limit = RunTimeout(definition.run_timeout_s, "bring-up")
    task_limit = RunTimeout(definition.run_timeout_s)
    try:
        draws = [(parameter, parameter.draw(seed)) for parameter in definition.randomization]
        for parameter, value in draws:
            row.update(parameter.row(value))
        restart_random_numbers(seed)
        # The limit is the task's: launching the world (reading models, which a busy
        # machine slows) has a limit of its own, so a slow bring-up never cuts a task short.
        with bringup_limit:
            task = task or definition.task.load()
            spec, keywords = apply_draws(definition.spec, draws)
            spec = replace(spec, world=replace(spec.world, viewer=False, realtime=False))
            world = launch(spec, viewer=False, models=models)
        row["bringup_s"] = time.perf_counter() - began
        task_began = time.perf_counter()
        with task_limit:
            metrics = task(world, np.random.default_rng(seed), **definition.parameters, **keywords)
            task_limit.cancel()  # closing the world must not be cut short
        row["task_s"] = time.perf_counter() - task_began
        row["stepping_s"] = world.stepping_s
        row["sim_time_s"] = world.time
        row["metrics"] = checked_metrics(metrics, reserved=(*RUN_COLUMNS, *row))
        row["ok"] = True
    except RunTimedOut as exc:
        row["error"] = f"{TIMED_OUT}: {exc}"
    except Exception as exc:  # the task's failure is this run's row, not the sweep's end
        row["error"] = _one_line(exc)
    finally:
        bringup_limit.cancel()
        task_limit.cancel()
        if world is not None:
            if row["sim_time_s"] is None and not world.closed:
                row["stepping_s"], row["sim_time_s"] = world.stepping_s, world.time
            world.close()
    row["wall_s"] = time.perf_counter() - began
    return row


def checked_metrics(metrics: object, reserved: tuple[str, ...]) -> dict[str, Metric]:
    """``metrics`` as plain Python values, or a ``TypeError`` saying what is wrong."""
    if not isinstance(metrics, dict):
        raise TypeError(
            f"the task returned a {type(metrics).__name__}; it must return a dict of metric "
            "names to numbers, bools or text"
        )
    checked: dict[str, Metric] = {}
    for name, value in metrics.items():
        if not isinstance(name, str) or not name:
            raise TypeError(f"metric name {name!r} is not text")
        if name in reserved:
            raise TypeError(f"metric name {name!r} is taken by a column of the results")
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, bool | str | int | float):
            checked[name] = value
        else:
            raise TypeError(
                f"metric {name!r} is a {type(value).__name__}; give a number, bool or text"
            )
    return checked


def _one_line(exc: BaseException) -> str:
    """``Type: message (at file:line)``, the line where it was raised."""
    text = " ".join(str(exc).split()) or "(no message)"
    frames = traceback.extract_tb(exc.__traceback__)
    where = f" (at {os.path.basename(frames[-1].filename)}:{frames[-1].lineno})" if frames else ""
    return f"{type(exc).__name__}: {text}{where}"[:MAX_ERROR_CHARS]
