"""How long another client waits while one client steps a paused shared world.

Starts ``armfleet spawn bob`` in a subprocess (its own runtime folder). One client
pauses the world and asks ``step N`` (100,000 by default); meanwhile another client
calls ``info`` every 50 ms and times each round trip. Before steps ran in slices, the
other client's first ``info`` waited for the whole step request (28.4 s for 100,000
steps with one Panda on the 2-core development machine). Results go to
``benchmarks/results/shared_world_fairness.json``.
Run: ``python benchmarks/shared_world_fairness.py [--steps N]``.
"""

from __future__ import annotations

import argparse
import json
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

import armfleet

RESULTS = Path(__file__).parent / "results" / "shared_world_fairness.json"
#: Period of the other client's ``info`` calls [s].
PROBE_PERIOD_S = 0.05


def start_world(runtime: Path) -> tuple[subprocess.Popen[str], str]:
    command = [sys.executable, "-m", "armfleet.cli.main", "spawn", "bob", "--at", "0,0"]
    command += ["--no-viewer", "--realtime"]
    env = os.environ | {"XDG_RUNTIME_DIR": str(runtime), "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=env)
    assert process.stdout is not None
    for line in process.stdout:
        if line.startswith("api: "):
            threading.Thread(target=process.stdout.read, daemon=True).start()
            return process, line.split()[1]
    raise RuntimeError("the world did not start")


def measure(address: str, steps: int) -> dict[str, Any]:
    """Step ``steps`` with one client while another times its ``info`` round trips."""
    with (
        armfleet.connect(address, timeout=600) as stepper,
        armfleet.connect(address, timeout=600) as other,
    ):
        stepper.pause()
        done = threading.Event()
        began = time.perf_counter()

        def step() -> None:
            stepper.step(steps)
            done.set()

        thread = threading.Thread(target=step)
        thread.start()
        round_trips: list[float] = []
        while not round_trips or not done.is_set():  # at least one, however short the step
            start = time.perf_counter()
            other.info()
            round_trips.append(time.perf_counter() - start)
            time.sleep(PROBE_PERIOD_S)
        thread.join()
        step_s = time.perf_counter() - began
        stepper.resume()
    return {
        "steps": steps,
        "step_request_s": step_s,
        "info_calls": len(round_trips),
        "info_median_ms": statistics.median(round_trips) * 1e3,
        "info_max_ms": max(round_trips) * 1e3,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100_000, help="steps of the long request")
    parser.add_argument("--json", type=Path, default=RESULTS, help="where to write the figures")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as runtime:
        process, address = start_world(Path(runtime))
        try:
            figures = measure(address, args.steps)
        finally:
            process.terminate()
            process.wait(timeout=60)
    figures["machine"] = {"cpus": os.cpu_count(), "load_1min": os.getloadavg()[0]}
    figures["python"] = platform.python_version()
    print(
        f"step {figures['steps']}: {figures['step_request_s']:.1f} s; another client's info "
        f"meanwhile: {figures['info_calls']} calls, median {figures['info_median_ms']:.1f} ms, "
        f"max {figures['info_max_ms']:.1f} ms"
    )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main()
