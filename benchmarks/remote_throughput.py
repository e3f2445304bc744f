"""Live API throughput and latency with 10 arms stepping.

Starts ``armfleet spawn`` with 10 Pandas in a subprocess (its own runtime folder),
then, from this process:

- joint-state messages per second delivered to one subscriber (one client
  subscribed to all 10 ``/<arm>/joint_states``), against what the world published
  (1 kHz per arm over the simulated time that passed), with the world's real-time
  factor with and without that subscriber;
- the round-trip time of a move command (``RemoteArm.move_to``: request, applied
  at a step boundary, reply), median and 95th percentile.

Both with the world paced to the wall clock (``--realtime``, the default of
``armfleet spawn``) and running flat out (``--fast``). Results go to
``benchmarks/results/remote.json``. Run: ``python benchmarks/remote_throughput.py``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

import armfleet
from armfleet.messages import JointState

ARMS = 10
#: The joint_state_broadcaster's default rate [Hz].
PUBLISH_RATE_HZ = 1000.0
RESULTS = Path(__file__).parent / "results" / "remote.json"


def start_world(runtime: Path, realtime: bool) -> tuple[subprocess.Popen[str], str]:
    names = [f"a{i}" for i in range(ARMS)]
    poses = [f"{i % 5},{i // 5}" for i in range(ARMS)]
    command = [sys.executable, "-m", "armfleet.cli.main", "spawn", *names, "--at", *poses]
    command += ["--no-viewer", "--realtime" if realtime else "--fast"]
    env = os.environ | {"XDG_RUNTIME_DIR": str(runtime), "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=env)
    assert process.stdout is not None
    for line in process.stdout:
        if line.startswith("api: "):
            # Keep reading its status lines, so that its stdout never fills up.
            threading.Thread(target=process.stdout.read, daemon=True).start()
            return process, line.split()[1]
    raise RuntimeError("the world did not start")


def cpu_seconds(pid: int) -> float:
    """CPU time process ``pid`` has used [s] (Linux; NaN elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return math.nan
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def world_cost(client: armfleet.remote.Client, pid: int, seconds: float) -> tuple[float, float]:
    """The world's real-time factor, and its CPU time per simulated second, over ``seconds``."""
    sim0, wall0, cpu0 = client.info().time_s, time.perf_counter(), cpu_seconds(pid)
    time.sleep(seconds)
    sim1, wall1, cpu1 = client.info().time_s, time.perf_counter(), cpu_seconds(pid)
    return (sim1 - sim0) / (wall1 - wall0), (cpu1 - cpu0) / (sim1 - sim0)


class Counter:
    """Counts one topic's messages, and the span of their stamps, within a window."""

    def __init__(self) -> None:
        self.counting = False
        self.count = 0
        self.first = self.last = 0.0

    def __call__(self, state: JointState) -> None:
        if self.counting:
            if not self.count:
                self.first = state.stamp
            self.count += 1
            self.last = state.stamp

    @property
    def published(self) -> float:
        """Messages the world published from the first to the last one counted."""
        return round((self.last - self.first) * PUBLISH_RATE_HZ) + 1 if self.count else 0


def measure_stream(client: armfleet.remote.Client, pid: int, seconds: float) -> dict[str, Any]:
    counters = [Counter() for _ in range(ARMS)]
    subscriptions = [
        client.subscribe(f"/a{i}/joint_states", counter, queue_size=1000)
        for i, counter in enumerate(counters)
    ]
    time.sleep(1.0)  # let the stream settle
    sim0, wall0, cpu0 = client.info().time_s, time.perf_counter(), cpu_seconds(pid)
    for counter in counters:
        counter.counting = True
    time.sleep(seconds)
    for counter in counters:
        counter.counting = False
    sim1, wall1, cpu1 = client.info().time_s, time.perf_counter(), cpu_seconds(pid)
    dropped = sum(s.dropped for s in subscriptions)
    for subscription in subscriptions:
        subscription.cancel()
    delivered = sum(c.count for c in counters)
    published = sum(c.published for c in counters)
    wall = wall1 - wall0
    return {
        "delivered_msgs_per_s": delivered / wall,
        "published_msgs_per_s": published / wall,
        "delivered_fraction": delivered / max(1, published),
        "dropped_total": dropped,
        "realtime_factor_with_subscriber": (sim1 - sim0) / wall,
        "world_cpu_s_per_sim_s_with_subscriber": (cpu1 - cpu0) / (sim1 - sim0),
    }


def measure_moves(client: armfleet.remote.Client, count: int) -> dict[str, Any]:
    arm = client.arm("a0")
    home = arm.positions
    offsets = (np.zeros(7), np.full(7, 0.02))
    rtts = []
    for k in range(count):
        started = time.perf_counter()
        arm.move_to(home + offsets[k % 2])
        rtts.append(time.perf_counter() - started)
    rtts_ms = sorted(1000.0 * r for r in rtts)
    return {
        "moves": count,
        "rtt_median_ms": statistics.median(rtts_ms),
        "rtt_p95_ms": rtts_ms[int(0.95 * (len(rtts_ms) - 1))],
        "rtt_max_ms": rtts_ms[-1],
    }


def run(realtime: bool, seconds: float, moves: int) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as runtime:
        process, address = start_world(Path(runtime), realtime)
        try:
            with armfleet.connect(address, timeout=30.0) as client:
                idle_rtf, idle_cpu = world_cost(client, process.pid, 2.0)
                latency = measure_moves(client, moves)
                stream = measure_stream(client, process.pid, seconds)
            return {
                "mode": "realtime" if realtime else "fast",
                "arms": ARMS,
                "realtime_factor_without_subscriber": idle_rtf,
                "world_cpu_s_per_sim_s_without_subscriber": idle_cpu,
                **stream,
                **latency,
            }
        finally:
            process.terminate()
            process.wait(timeout=60)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="stream window [s]")
    parser.add_argument("--moves", type=int, default=200, help="move commands timed")
    args = parser.parse_args()
    results = [run(realtime, args.seconds, args.moves) for realtime in (True, False)]
    for r in results:
        print(
            f"{r['mode']:>8}: {r['delivered_msgs_per_s']:7.0f} joint-state msgs/s delivered "
            f"to one subscriber (world published {r['published_msgs_per_s']:.0f}/s, "
            f"{100 * r['delivered_fraction']:.1f}% delivered, {r['dropped_total']} dropped); "
            f"RTF {r['realtime_factor_without_subscriber']:.2f} without / "
            f"{r['realtime_factor_with_subscriber']:.2f} with the subscriber, world CPU "
            f"{r['world_cpu_s_per_sim_s_without_subscriber']:.2f} / "
            f"{r['world_cpu_s_per_sim_s_with_subscriber']:.2f} s per simulated s; "
            f"move round trip median {r['rtt_median_ms']:.2f} ms, p95 {r['rtt_p95_ms']:.2f} ms"
        )
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    report = {
        "command": "python benchmarks/remote_throughput.py",
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average_1min": os.getloadavg()[0],
        },
        "armfleet": armfleet.__version__,
        "results": results,
    }
    RESULTS.write_text(json.dumps(report, indent=2) + "\n")
    print(f"written to {RESULTS}")


if __name__ == "__main__":
    main()
