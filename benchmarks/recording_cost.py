"""What recording every topic to MCAP costs the simulation, and how big the files get.

For N Pandas (default 10, a grid 1 m apart, random targets inside the joint
limits) this runs the same workload flat out in three worlds of one process,
alternating chunks of simulated time:

* ``off``: nothing listens;
* ``tap``: a listener on every topic that does nothing. That alone makes the
  world publish ``/tf`` and ``/<arm>/position_controller/state`` (computed only
  for listeners): the world's share of the recording cost;
* ``record``: an :class:`armfleet.Recorder` on every topic.

It reports the real-time factor (simulated time / wall time) of each, the
ratios, the file size per arm and simulated minute, and the process's
resident memory before and after the recorded runs (the recorder keeps a
bounded batch and one chunk, whatever the length). Results go to
``benchmarks/results/recording.json``.

Run: ``python benchmarks/recording_cost.py [--arms 10] [--chunk 1.0] [--repeats 5]``
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import statistics
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scenarios import grid_spawn, timed_run  # benchmarks/ is the script's folder

import armfleet

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "recording.json"


@dataclass
class Result:
    """Figures for one fleet size."""

    arms: int
    sim_s_per_run: float
    rtf_off: float
    rtf_tap: float
    rtf_record: float
    ratio_record_off: float
    ratio_tap_off: float
    recorded_sim_s: float
    messages: int
    file_mb: float
    mb_per_arm_minute: float
    rss_mb_before: float
    rss_mb_after: float


def rss_mb() -> float:
    """Resident memory of this process [MB]."""
    with open("/proc/self/statm") as statm:
        pages = int(statm.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def measure(count: int, chunk_s: float, repeats: int, folder: Path) -> Result:
    print(f"\n== {count} arms, {repeats} x {chunk_s} s simulated per mode")
    worlds = {mode: armfleet.World() for mode in ("off", "tap", "record")}
    try:
        for world in worlds.values():
            grid_spawn(world, count)
        worlds["tap"].bus.subscribe_all(lambda topic, message: None)
        path = folder / f"recording_{count}_arms.mcap"
        rngs = {mode: np.random.default_rng(count) for mode in worlds}
        for mode, world in worlds.items():  # warm-up: caches, allocations
            timed_run(world, rngs[mode], 1.0)
        recorder = armfleet.record(worlds["record"], path)
        recorded_from = worlds["record"].time
        rss_before = rss_mb()
        rtf: dict[str, list[float]] = {mode: [] for mode in worlds}
        for _ in range(repeats):
            for mode, world in worlds.items():
                rtf[mode].append(chunk_s / timed_run(world, rngs[mode], chunk_s))
        rss_after = rss_mb()
        recorded_s = worlds["record"].time - recorded_from
        recorder.stop()
        size_mb = path.stat().st_size / 1e6
        medians = {mode: statistics.median(values) for mode, values in rtf.items()}
        for mode, values in rtf.items():
            print(f"   RTF {mode:<6} {[round(v, 3) for v in values]}")
        return Result(
            arms=count,
            sim_s_per_run=chunk_s,
            rtf_off=round(medians["off"], 3),
            rtf_tap=round(medians["tap"], 3),
            rtf_record=round(medians["record"], 3),
            ratio_record_off=round(medians["record"] / medians["off"], 3),
            ratio_tap_off=round(medians["tap"] / medians["off"], 3),
            recorded_sim_s=round(recorded_s, 3),
            messages=recorder.message_count,
            file_mb=round(size_mb, 2),
            mb_per_arm_minute=round(size_mb / count / (recorded_s / 60.0), 1),
            rss_mb_before=round(rss_before, 1),
            rss_mb_after=round(rss_after, 1),
        )
    finally:
        for world in worlds.values():
            world.close()


def print_table(results: list[Result]) -> None:
    header = (
        f"{'arms':>4} | {'RTF off':>8} | {'RTF tap':>8} | {'RTF rec':>8} | {'rec/off':>7} | "
        f"{'MB/arm-min':>10} | {'RSS before->after':>17}"
    )
    print("\n" + header + "\n" + "-" * len(header))
    for r in results:
        print(
            f"{r.arms:>4} | {r.rtf_off:>8.2f} | {r.rtf_tap:>8.2f} | {r.rtf_record:>8.2f} | "
            f"{r.ratio_record_off:>7.3f} | {r.mb_per_arm_minute:>10.1f} | "
            f"{r.rss_mb_before:>7.0f} -> {r.rss_mb_after:<6.0f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", type=int, nargs="+", default=[10])
    parser.add_argument("--chunk", type=float, default=1.0, help="simulated s per timed run")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per mode")
    parser.add_argument("--keep", type=Path, default=None, help="folder to keep the MCAP files in")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    with tempfile.TemporaryDirectory(prefix="armfleet-recording-") as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        results = [measure(n, args.chunk, args.repeats, folder) for n in args.arms]
    print_table(results)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average": os.getloadavg(),
        },
        "command": f"python benchmarks/recording_cost.py --arms {' '.join(map(str, args.arms))} "
        f"--chunk {args.chunk} --repeats {args.repeats}",
        "results": [asdict(r) for r in results],
    }
    RESULTS.write_text(json.dumps(report, indent=2) + "\n")
    print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
