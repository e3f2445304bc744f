"""What serving a world to ROS 2 costs the simulation (issue 29, item 4).

For 2, 10 and 30 Pandas (a grid 1 m apart, random targets inside the joint limits),
the same workload runs flat out in chunks of simulated time, alternating three modes in
one process:

* ``off``: no ROS 2 interface;
* ``on``: ``world.serve_ros()`` at the default rate (100 instants per simulated second),
  nobody subscribed;
* ``subscribed``: the same with one ROS 2 node, in a process of its own, subscribed to
  ``/clock``, ``/tf`` and every arm's ``joint_states`` and reading them.

It reports the CPU time of the world's process per step (every thread: the stepping one
and the ROS executor's) and the wall time per step, the ratios to ``off`` measured in the
same run, and what the node received. Results go to ``benchmarks/results/ros_overhead.json``.

Run: ``python benchmarks/ros_overhead.py [--arms 2 10 30] [--chunk 1.0] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import select
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scenarios import grid_spawn, retarget  # benchmarks/ is the script's folder

import armfleet
from armfleet.ros import loopback_environment

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "ros_overhead.json"
MODES = ("off", "on", "subscribed")
DOMAIN = 199

SUBSCRIBER = """
import sys, threading, rclpy
from rclpy.executors import SingleThreadedExecutor
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage
arms = sys.argv[2:]
ctx = rclpy.Context(); rclpy.init(context=ctx, domain_id=int(sys.argv[1]))
node = rclpy.create_node("benchmark_subscriber", context=ctx)
count = [0]
heard = set()
def listen(topic):
    def got(_message):
        count[0] += 1
        if topic not in heard:
            heard.add(topic)
            if len(heard) == 2 + len(arms):
                print("receiving", flush=True)
    return got
node.create_subscription(Clock, "/clock", listen("/clock"), 10)
node.create_subscription(TFMessage, "/tf", listen("/tf"), 100)
for arm in arms:
    node.create_subscription(JointState, f"/{arm}/joint_states", listen(arm), 10)
executor = SingleThreadedExecutor(context=ctx); executor.add_node(node)
done = threading.Event()
threading.Thread(target=lambda: (sys.stdin.read(), done.set()), daemon=True).start()
print("subscribed", flush=True)
while not done.is_set():  # until the benchmark closes our stdin
    executor.spin_once(timeout_sec=0.1)
print(count[0], flush=True)
"""


def _chunk(world: armfleet.World, rng: np.random.Generator, sim_s: float) -> tuple[float, float]:
    """CPU and wall seconds of ``sim_s`` simulated seconds flat out (targets every 0.5 s)."""
    cpu = wall = 0.0
    for _ in range(max(1, round(sim_s / 0.5))):
        retarget(world, rng)
        started_cpu, started = time.process_time(), time.perf_counter()
        world.run(0.5)
        cpu += time.process_time() - started_cpu
        wall += time.perf_counter() - started
    return cpu, wall


def _subscriber(arms: list[str]) -> subprocess.Popen[str]:
    process = subprocess.Popen(
        [sys.executable, "-c", SUBSCRIBER, str(DOMAIN), *arms],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=os.environ | loopback_environment(),
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "subscribed"
    return process


def _until_receiving(world: armfleet.World, node: subprocess.Popen[str]) -> None:
    """Step the world at the wall clock until the node hears every topic (discovery)."""
    assert node.stdout is not None
    deadline = time.monotonic() + 120.0
    while not select.select([node.stdout], [], [], 0)[0]:
        if time.monotonic() > deadline:
            raise RuntimeError("the subscriber heard nothing in 120 s")
        world.run(0.05, realtime=True)
    assert node.stdout.readline().strip() == "receiving"


def measure(arms: int, chunk_s: float, repeats: int) -> dict[str, Any]:
    rng = np.random.default_rng(arms)
    world = armfleet.World()
    grid_spawn(world, arms)
    names = list(world.arms)
    steps = round(chunk_s / world.dt)
    samples: dict[str, list[tuple[float, float]]] = {mode: [] for mode in MODES}
    received = []
    try:
        for _ in range(repeats):
            samples["off"].append(_chunk(world, rng, chunk_s))
            server = world.serve_ros(DOMAIN)
            try:
                samples["on"].append(_chunk(world, rng, chunk_s))
                node = _subscriber(names)
                try:
                    _until_receiving(world, node)
                    samples["subscribed"].append(_chunk(world, rng, chunk_s))
                finally:
                    out, _ = node.communicate(input="", timeout=60)
                    received.append(int(out.split()[-1]))
            finally:
                server.close()
    finally:
        world.close()
    result: dict[str, Any] = {"arms": arms, "steps_per_chunk": steps, "received": received}
    for mode in MODES:
        cpu = statistics.median(c for c, _ in samples[mode]) / steps * 1e3
        wall = statistics.median(w for _, w in samples[mode]) / steps * 1e3
        result[mode] = {"cpu_ms_per_step": cpu, "wall_ms_per_step": wall}
    for mode in ("on", "subscribed"):
        result[mode]["cpu_ratio_to_off"] = (
            result[mode]["cpu_ms_per_step"] / result["off"]["cpu_ms_per_step"]
        )
        result[mode]["wall_ratio_to_off"] = (
            result[mode]["wall_ms_per_step"] / result["off"]["wall_ms_per_step"]
        )
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", type=int, nargs="+", default=[2, 10, 30])
    parser.add_argument("--chunk", type=float, default=1.0, help="simulated s per chunk")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", type=Path, default=RESULTS)
    args = parser.parse_args()
    rows = []
    print(f"{'arms':>4} {'mode':>10} {'CPU ms/step':>12} {'wall ms/step':>13} {'CPU ratio':>9}")
    for arms in args.arms:
        row = measure(arms, args.chunk, args.repeats)
        rows.append(row)
        for mode in MODES:
            figures = row[mode]
            ratio = figures.get("cpu_ratio_to_off", 1.0)
            print(
                f"{arms:>4} {mode:>10} {figures['cpu_ms_per_step']:>12.3f} "
                f"{figures['wall_ms_per_step']:>13.3f} {ratio:>9.2f}"
            )
        print(f"     the node received {row['received']} messages per chunk", flush=True)
    report = {
        "benchmark": "ros_overhead",
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "load_average": os.getloadavg(),
        "chunk_simulated_s": args.chunk,
        "repeats": args.repeats,
        "rows": rows,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
