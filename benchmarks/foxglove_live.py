"""What serving a world to Foxglove costs the simulation, with and without clients.

For N Pandas (default 10, a grid 1 m apart, random targets inside the joint
limits) this runs the same workload flat out in four worlds of one process,
alternating chunks of simulated time:

* ``none``: no Foxglove server;
* ``idle``: a server nobody is connected to (every channel advertised, nothing
  subscribed: the bus sees no listener);
* ``layout``: a server with one client, in a process of its own, subscribed to what
  the layout of docs/foxglove.md shows (``/tf``, ``/tf_static``, the robot descriptions,
  one arm's joint states) and reading it;
* ``all``: a server with one client subscribed to every channel and reading everything,
  the streams (``/tf``, joint and controller states) at the default 100 Hz of simulated
  time;
* ``every``: the same with the streams at every step (``rate_hz=None``, 1 kHz): ``/tf``
  and the controller states are then computed, encoded and sent at every step, the
  world's whole share of the heaviest Foxglove session;
* ``slow``: a server (streams at every step) with one client subscribed to every
  channel that never reads
  (its socket fills, then the server's 1,024-message queue drops the oldest).

It reports the real-time factor (simulated time / wall time) of each, the ratios to
``none``, the mean step time, the messages handed to the server per simulated second,
and what the reading client received. Results go to
``benchmarks/results/foxglove_live.json`` (or ``--json PATH``).

Run: ``python benchmarks/foxglove_live.py [--arms 10] [--chunk 1.0] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import signal
import statistics
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np
from scenarios import grid_spawn, timed_run  # benchmarks/ is the script's folder

import armfleet
from armfleet.foxglove import FoxgloveServer, serve_foxglove

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "foxglove_live.json"
MODES = ("none", "idle", "layout", "all", "every", "slow")
#: What each client subscribes to: the topics of docs/foxglove.md's layout, or every one.
CLIENTS = {"layout": "layout", "all": "read", "every": "read", "slow": "slow"}
#: Streams at every step (None) or at the server's default display rate.
EVERY_STEP = ("every", "slow")
#: Longest wait for a client to connect and its subscriptions to take effect [s].
SETTLE_S = 30.0


@dataclass
class Result:
    """Figures for one fleet size."""

    arms: int
    sim_s_per_run: float
    repeats: int
    rtf: dict[str, float]
    ratio_to_none: dict[str, float]
    step_us: dict[str, float]
    channels: int
    messages_per_sim_s: dict[str, float]
    client_received: int
    client_received_mb: float
    client_share_of_sent: float


# -- the client, run as a process of its own ---------------------------------------------
def run_client(url: str, mode: str) -> None:
    """Subscribe to the channels of ``url`` that ``mode`` wants (``layout``: the documented
    layout's; ``read``, ``slow``: all); read them (``slow``: never) until SIGTERM, then print
    what was received as JSON."""
    read = mode != "slow"
    from websockets.sync.client import connect
    from websockets.typing import Subprotocol

    def stop(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    ws = connect(
        url, subprotocols=[Subprotocol("foxglove.sdk.v1")], proxy=None, max_size=None,
        max_queue=None if read else 1, close_timeout=0.5, legacy=True,
        ping_interval=None,  # a client that never reads would time itself out on its pings
    )  # fmt: skip
    channels: list[dict[str, Any]] = []
    wait_s = SETTLE_S
    while True:  # the advertisements, until the server has nothing more to say
        try:
            frame = ws.recv(timeout=wait_s)
        except TimeoutError:
            break
        if isinstance(frame, str):
            channels += json.loads(frame).get("channels", [])
        if any(c["topic"].endswith("robot_description") for c in channels):
            wait_s = 0.3
    if mode == "layout":
        shown = ("/tf", "/tf_static", "/arm0/joint_states")
        channels = [
            c for c in channels if c["topic"] in shown or c["topic"].endswith("/robot_description")
        ]
    subscriptions = [{"id": i, "channelId": c["id"]} for i, c in enumerate(channels)]
    ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
    print(json.dumps({"subscribed": len(subscriptions)}), flush=True)
    received = received_bytes = 0
    try:
        while True:
            if not read:
                time.sleep(1.0)
                continue
            frame = ws.recv()
            if isinstance(frame, bytes) and frame[:1] == b"\x01":
                received += 1
                received_bytes += len(frame)
    except (KeyboardInterrupt, Exception):
        pass
    print(json.dumps({"received": received, "bytes": received_bytes}), flush=True)


# -- the worlds ------------------------------------------------------------------------
def start_client(url: str, mode: str) -> tuple[subprocess.Popen[str], int]:
    """A client process of ``mode``, once subscribed; and how many channels it took."""
    command = [sys.executable, __file__, "--client", url, "--client-mode", mode]
    client = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    assert client.stdout is not None
    line = client.stdout.readline()
    if not line:
        raise RuntimeError(f"the {mode} client did not subscribe")
    return client, int(json.loads(line)["subscribed"])


def serve(world: armfleet.World, mode: str) -> FoxgloveServer:
    """``world`` served as ``mode`` wants: its streams at every step, or at the default."""
    if mode in EVERY_STEP:
        return serve_foxglove(world, 0, rate_hz=None)
    return serve_foxglove(world, 0)


def measure(count: int, chunk_s: float, repeats: int) -> Result:
    print(f"\n== {count} arms, {repeats} x {chunk_s} s simulated per mode")
    worlds = {mode: armfleet.World() for mode in MODES}
    clients: dict[str, subprocess.Popen[str]] = {}
    try:
        for world in worlds.values():
            grid_spawn(world, count)
            world.run(0.2)  # every topic advertised (the arms' status: 10 Hz)
        servers = {mode: serve(worlds[mode], mode) for mode in MODES if mode != "none"}
        for mode, client_mode in CLIENTS.items():
            clients[mode], subscribed = start_client(servers[mode].url, client_mode)
            wanted = subscribed - count  # the robot descriptions are no bus topics
            deadline = time.monotonic() + SETTLE_S
            while len(servers[mode].listened) < wanted and time.monotonic() < deadline:
                # Subscribed without stepping: once messages flow, the SDK may leave the rest
                # of a subscribe request of a client that does not read unprocessed.
                worlds[mode].process_requests()
                time.sleep(0.01)
            print(f"   {mode}: listening to {len(servers[mode].listened)} bus topics")
        rngs = {mode: np.random.default_rng(count) for mode in MODES}
        for mode, world in worlds.items():  # warm-up: caches, allocations
            timed_run(world, rngs[mode], 0.5)
        rtf: dict[str, list[float]] = {mode: [] for mode in MODES}
        sent = {mode: 0 for mode in MODES}
        for _ in range(repeats):
            for mode, world in worlds.items():
                before = servers[mode].messages_sent if mode in servers else 0
                rtf[mode].append(chunk_s / timed_run(world, rngs[mode], chunk_s))
                sent[mode] += (servers[mode].messages_sent if mode in servers else 0) - before
        reports = {mode: finish_client(clients.pop(mode)) for mode in CLIENTS}
        report = reports["all"]
        medians = {mode: statistics.median(values) for mode, values in rtf.items()}
        for mode, values in rtf.items():
            print(f"   RTF {mode:<5} {[round(v, 3) for v in values]}")
        dt = worlds["none"].dt
        total_sim = chunk_s * repeats
        return Result(
            arms=count,
            sim_s_per_run=chunk_s,
            repeats=repeats,
            rtf={mode: round(value, 3) for mode, value in medians.items()},
            ratio_to_none={mode: round(medians[mode] / medians["none"], 3) for mode in MODES},
            step_us={mode: round(dt / medians[mode] * 1e6, 1) for mode in MODES},
            channels=len(servers["all"].topics),
            messages_per_sim_s={mode: round(sent[mode] / total_sim) for mode in MODES},
            client_received=report.get("received", 0),
            client_received_mb=round(report.get("bytes", 0) / 1e6, 1),
            client_share_of_sent=round(
                report.get("received", 0) / max(1, servers["all"].messages_sent), 3
            ),
        )
    finally:
        for client in clients.values():
            client.kill()
        for world in worlds.values():
            world.close()


def finish_client(client: subprocess.Popen[str]) -> dict[str, Any]:
    """Stop a client; what it received."""
    client.send_signal(signal.SIGTERM)
    try:
        out, _ = client.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        client.kill()
        out, _ = client.communicate()
    lines = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    return lines[-1] if lines else {}


def print_table(results: list[Result]) -> None:
    header = (
        f"{'arms':>4} | {'mode':<5} | {'RTF':>6} | {'/none':>6} | {'step us':>8} | "
        f"{'msgs/sim s':>10}"
    )
    print("\n" + header + "\n" + "-" * len(header))
    for r in results:
        for mode in MODES:
            print(
                f"{r.arms:>4} | {mode:<5} | {r.rtf[mode]:>6.2f} | {r.ratio_to_none[mode]:>6.3f} | "
                f"{r.step_us[mode]:>8.0f} | {r.messages_per_sim_s[mode]:>10}"
            )
        print(
            f"     reading client: {r.client_received} messages, {r.client_received_mb} MB "
            f"({r.client_share_of_sent:.0%} of those handed to the server; the rest were "
            "dropped by its queue)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", type=int, nargs="+", default=[10])
    parser.add_argument("--chunk", type=float, default=1.0, help="simulated s per timed run")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per mode")
    parser.add_argument("--json", type=Path, default=RESULTS, help="where to write the figures")
    parser.add_argument("--client", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--client-mode", default="read", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.client is not None:
        run_client(args.client, args.client_mode)
        return
    logging.basicConfig(level=logging.WARNING)
    results = [measure(n, args.chunk, args.repeats) for n in args.arms]
    print_table(results)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average": os.getloadavg(),
        },
        "command": f"python benchmarks/foxglove_live.py --arms {' '.join(map(str, args.arms))} "
        f"--chunk {args.chunk} --repeats {args.repeats}",
        "results": [asdict(r) for r in results],
    }
    args.json.write_text(json.dumps(report, indent=2) + "\n")
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
