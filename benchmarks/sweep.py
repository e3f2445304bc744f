"""Sweep benchmark: the same runs in a plain in-process loop, on Ray with 1 worker, and on
Ray with 2 workers; Ray's overhead per run; and a projection to bigger machines.

For one scenario (default ``reach``) and the seeds ``0 .. runs-1`` it measures:
  loop     - ``run_seed`` for every seed, one after the other, in this process (what a
             user writes without Ray);
  ray x1   - ``armfleet.sweep(..., workers=1)``: a private local Ray, batches of runs;
  ray x2   - the same with 2 workers.
Ray's start-up (``ray.init``, the workers' first import of armfleet) is timed apart from
the runs: the runs' throughput is the driver's time from the first batch to the last row.
It prints runs per second, the speedup at 2 workers over the loop (target >= 1.8x), Ray's
overhead per run, where a run's time goes (bring-up, simulation, the rest of the task,
closing), the results' size per row, an empty-task round trip measured here, and the
throughput projected to a 64-core machine and a 10-machine cluster, with its
assumptions; and writes benchmarks/results/sweep.json.

    python benchmarks/sweep.py                    # 200 runs of reach, 2 turns (~8 minutes)
    python benchmarks/sweep.py --runs 20          # a quick look
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import json
import os
import pickle
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from armfleet.description import ModelLibrary
from armfleet.sweeps.definition import load_sweep
from armfleet.sweeps.ray_session import ray_session
from armfleet.sweeps.run import run_seed

RESULTS = Path(__file__).resolve().parent / "results"

#: Ray's own scheduling figure, from its release benchmarks (release_logs/2.20.0/
#: benchmarks/many_tasks.json: 10,000 tasks over a 2,500-CPU cluster, 582 tasks/s end to
#: end). The projection assumes a cluster's driver cannot hand out more than this.
RAY_PUBLISHED_TASKS_PER_S = 582.0
#: The projection's machines.
BIG_MACHINE_CORES = 64
CLUSTER_MACHINES, CLUSTER_CORES_EACH = 10, 64


def timed_loop(scenario: str, runs: int) -> dict[str, Any]:
    """The loop a user writes: one task and one model library for every run (as a Ray
    batch has), so that the difference to Ray is Ray's."""
    definition = load_sweep(scenario)
    task = definition.task.load()
    models = ModelLibrary()
    began = time.perf_counter()
    rows = [run_seed(definition, seed, task, models) for seed in range(runs)]
    wall = time.perf_counter() - began
    return {"wall_s": wall, "runs_per_s": runs / wall, "rows": rows}


def timed_ray(scenario: str, runs: int, workers: int) -> dict[str, Any]:
    began = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        result = armfleet.sweep(
            scenario,
            runs=runs,
            workers=workers,
            output=Path(folder) / "r.parquet",
            progress=False,
        )
        size = (Path(folder) / "r.parquet").stat().st_size
    total = time.perf_counter() - began
    rows = result.table.to_pylist()
    counts = result.counts
    return {
        "workers": workers,
        "total_s": total,
        "runs_wall_s": counts.wall_s,
        "startup_s": total - counts.wall_s,
        "runs_per_s": runs / counts.wall_s,
        "failed": counts.failed,
        "parquet_bytes_per_row": size / runs,
        "driver_s_per_batch": counts.driver_s / max(1, counts.batches),
        "batches": counts.batches,
        "rows": rows,
    }


def empty_task_round_trip(count: int = 200) -> dict[str, float]:
    """Ray's cost of a task that does nothing: pipelined and one at a time [s]."""
    with ray_session(None, 1) as session:
        ray = session.ray

        @ray.remote(num_cpus=1)  # type: ignore[untyped-decorator]
        def nothing() -> None:
            return None

        ray.get(nothing.remote())  # the worker is up
        began = time.perf_counter()
        ray.get([nothing.remote() for _ in range(count)])
        pipelined = (time.perf_counter() - began) / count
        began = time.perf_counter()
        for _ in range(count // 4):
            ray.get(nothing.remote())
        blocking = (time.perf_counter() - began) / (count // 4)
    return {"pipelined_s": pipelined, "blocking_s": blocking}


def breakdown(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Mean seconds per run: bring-up, simulation, the task's other work, closing."""
    ok = [r for r in rows if r["ok"]]

    def mean(key: str) -> float:
        return statistics.fmean(r[key] for r in ok)

    return {
        "bringup_s": mean("bringup_s"),
        "stepping_s": mean("stepping_s"),
        "task_other_s": mean("task_s") - mean("stepping_s"),
        "close_and_draw_s": mean("wall_s") - mean("bringup_s") - mean("task_s"),
        "wall_s": mean("wall_s"),
        "sim_time_s": mean("sim_time_s"),
    }


def same_rows(loop: list[dict[str, Any]], ray: list[dict[str, Any]], columns: list[str]) -> bool:
    by_seed = {row["seed"]: row for row in ray}
    for row in loop:
        flat = {**row, **row["metrics"]}
        other = by_seed[row["seed"]]
        for column in columns:
            a, b = flat.get(column), other.get(column)
            if a != b and not (isinstance(a, float) and a != a and b != b):
                return False
    return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="reach")
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument(
        "--repeats", type=int, default=2, help="turns of the three modes (medians reported)"
    )
    args = parser.parse_args()
    runs = args.runs
    print(f"sweep benchmark: {runs} runs of {args.scenario} on {os.cpu_count()} cores", flush=True)
    turns: list[tuple[dict[str, Any], dict[str, Any], dict[str, Any]]] = []
    for turn in range(args.repeats):  # the modes take turns: a drift of the machine hits all
        loop = timed_loop(args.scenario, runs)
        one = timed_ray(args.scenario, runs, 1)
        two = timed_ray(args.scenario, runs, 2)
        turns.append((loop, one, two))
        print(
            f"turn {turn + 1}: loop {loop['runs_per_s']:.2f}, ray x1 {one['runs_per_s']:.2f}, "
            f"ray x2 {two['runs_per_s']:.2f} runs/s (x2 over loop "
            f"{two['runs_per_s'] / loop['runs_per_s']:.2f})",
            flush=True,
        )
    speedups = [two["runs_per_s"] / loop["runs_per_s"] for loop, _, two in turns]
    loop, one, two = turns[speedups.index(statistics.median_low(speedups))]
    trip = empty_task_round_trip()
    cost = breakdown(loop["rows"])
    definition = load_sweep(args.scenario)
    metrics = list(loop["rows"][0]["metrics"]) if loop["rows"][0]["ok"] else []
    columns = ["ok", *definition.parameter_columns, *metrics]
    identical = same_rows(loop["rows"], one["rows"], columns) and same_rows(
        loop["rows"], two["rows"], columns
    )
    overhead_1 = (one["runs_wall_s"] - loop["wall_s"]) / runs
    speedup = statistics.median(speedups)
    row_bytes = len(pickle.dumps(loop["rows"][0]))
    per_run_s = loop["wall_s"] / runs
    batch = max(1, min(64, int(2.0 / per_run_s)))
    efficiency_2 = speedup / 2

    driver_tasks_per_s = 1.0 / two["driver_s_per_batch"]  # rows taken and written per second

    def projected(cores: int) -> dict[str, float]:
        compute = cores * efficiency_2 / per_run_s  # runs/s if the cores scale as 2 did
        tasks_needed = compute / batch
        ceiling = min(RAY_PUBLISHED_TASKS_PER_S, driver_tasks_per_s) * batch
        return {
            "cores": cores,
            "runs_per_s": min(compute, ceiling),
            "tasks_per_s": tasks_needed,
            "result_mb_per_s": min(compute, ceiling) * row_bytes / 1e6,
            "scheduler_bound": compute > ceiling,
        }

    machine = projected(BIG_MACHINE_CORES)
    cluster = projected(CLUSTER_MACHINES * CLUSTER_CORES_EACH)

    print()
    print(f"{'mode':<10} {'runs/s':>8} {'wall s':>8} {'start-up s':>11} {'vs loop':>8}")
    print(f"{'loop':<10} {loop['runs_per_s']:>8.2f} {loop['wall_s']:>8.1f} {'-':>11} {1.0:>8.2f}")
    for mode, data in (("ray x1", one), ("ray x2", two)):
        print(
            f"{mode:<10} {data['runs_per_s']:>8.2f} {data['runs_wall_s']:>8.1f} "
            f"{data['startup_s']:>11.1f} {data['runs_per_s'] / loop['runs_per_s']:>8.2f}"
        )
    print(f"(the turn shown is the one with the median speedup; {len(turns)} turns)")
    print(
        f"speedup at 2 workers over the loop: {speedup:.2f}x median "
        f"(turns: {', '.join(f'{s:.2f}' for s in speedups)}; target >= 1.8x)"
    )
    print(
        f"Ray's overhead per run (1 worker vs loop): {overhead_1 * 1e3:.1f} ms; an empty task: "
        f"{trip['pipelined_s'] * 1e3:.2f} ms pipelined, {trip['blocking_s'] * 1e3:.2f} ms blocking"
    )
    print(f"rows equal to the loop's, bit for bit (parameters and metrics): {identical}")
    print(
        f"a run ({cost['wall_s'] * 1e3:.0f} ms, {cost['sim_time_s']:.2f} s simulated): bring-up "
        f"{cost['bringup_s'] * 1e3:.0f} ms, simulation {cost['stepping_s'] * 1e3:.0f} ms, rest of "
        f"the task {cost['task_other_s'] * 1e3:.0f} ms, "
        f"closing {cost['close_and_draw_s'] * 1e3:.0f} ms"
    )
    print(f"a row: {row_bytes} bytes pickled, {two['parquet_bytes_per_row']:.0f} bytes in Parquet")
    print(
        f"the driver: {two['driver_s_per_batch'] * 1e3:.2f} ms per batch to take and write its "
        f"rows ({two['batches']} batches), a ceiling of {driver_tasks_per_s:.0f} batches/s"
    )
    print(
        f"projection (batches of {batch} runs, {efficiency_2:.0%} of linear per core as at 2, "
        f"the lower of Ray's published {RAY_PUBLISHED_TASKS_PER_S:.0f} tasks/s and the "
        f"driver's {driver_tasks_per_s:.0f} batches/s as the ceiling):"
    )
    for name, data in (("64-core machine", machine), ("10 x 64-core cluster", cluster)):
        bound = "scheduler- or driver-bound" if data["scheduler_bound"] else "compute-bound"
        print(
            f"  {name}: {data['runs_per_s']:.0f} runs/s ({data['tasks_per_s']:.0f} tasks/s, "
            f"{data['result_mb_per_s']:.2f} MB/s of rows; {bound})"
        )
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "sweep.json"
    for turn_data in turns:
        for data in turn_data:
            data.pop("rows", None)
    out.write_text(
        json.dumps(
            {
                "scenario": args.scenario,
                "runs": runs,
                "cores": os.cpu_count(),
                "python": sys.version.split()[0],
                "loop": loop,
                "ray_1": one,
                "ray_2": two,
                "speedup_2_over_loop": speedup,
                "speedups_per_turn": speedups,
                "ray_overhead_per_run_s": overhead_1,
                "empty_task": trip,
                "run_breakdown": cost,
                "rows_identical_to_loop": identical,
                "row_bytes_pickled": row_bytes,
                "projection": {
                    "batch": batch,
                    "driver_batches_per_s": driver_tasks_per_s,
                    "machine": machine,
                    "cluster": cluster,
                },
            },
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
