"""What the MeshCat viewer costs the simulation, and how fast a browser shows the scene.

For 2 and 10 Pandas (a grid 1 m apart, random targets near home inside the
joint limits) this runs the same workload flat out in two worlds of one
process, one without and one with a viewer, alternating runs, and reports:

- the real-time factor (simulated time / wall time) of each and their ratio;
- the CPU time spent per simulated second (this process with all its threads,
  plus the viewer's server process), which other load on the machine
  disturbs less than wall time;
- with Debian's Chromium at /usr/bin/chromium: the time until a headless page
  shows every mesh of every arm, and the real-time factor while that page is
  open (with software WebGL the browser then competes for the same CPU).

Results go to ``benchmarks/results/viewer_cost.json``; screenshots to
``test-artifacts/``.

Run: ``python benchmarks/viewer_cost.py [--arms 2 10] [--chunk SIM_S] [--repeats 15]``
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import statistics
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scenarios import grid_spawn, retarget  # benchmarks/ is the script's folder

import armfleet
import armfleet.viewer
from armfleet.viewer import Viewer
from armfleet.viewer.headless_chromium import CHROMIUM, CHROMIUM_FLAGS

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "viewer_cost.json"
ARTIFACTS = ROOT / "test-artifacts"
PANDA_MESHES = 11
MESHES_LOADED_JS = """
(expected) => {
  if (typeof viewer === "undefined" || !viewer.scene_tree) return false;
  const fleet = viewer.scene_tree.children["meshcat"]
    && viewer.scene_tree.children["meshcat"].children["armfleet"];
  if (!fleet) return false;
  return Object.keys(expected).every((name) => {
    const arm = fleet.children[name];
    const visuals = arm && arm.children["visuals"];
    let meshes = 0;
    if (visuals) visuals.object.traverse((o) => { if (o.isMesh) meshes += 1; });
    return meshes >= expected[name];
  });
}
"""


@dataclass
class Result:
    """Figures for one fleet size."""

    arms: int
    sim_s_per_run: float
    runs: int
    rtf_viewer_off: float
    rtf_viewer_on: float
    ratio_on_off: float
    #: Median over back-to-back (off, on) pairs of RTF on / RTF off.
    ratio_on_off_paired: float
    #: CPU seconds per simulated second: simulation process (median of the runs)
    #: plus the viewer's server (total over the runs).
    cpu_s_per_sim_s_off: float
    cpu_s_per_sim_s_on: float
    cpu_overhead: float
    rtf_viewer_on_page_open: float | None
    full_scene_in_browser_s: float | None
    tick_not_due_us: float
    #: One display update of all (moving) arms, sent and acknowledged [ms].
    display_update_ms: float
    spawn_s_viewer_off: float
    spawn_s_viewer_on: float


@dataclass
class Sample:
    """One timed run: simulated, wall and CPU time [s]."""

    sim_s: float
    wall_s: float
    cpu_s: float

    @property
    def rtf(self) -> float:
        return self.sim_s / self.wall_s

    @property
    def cpu_per_sim_s(self) -> float:
        return self.cpu_s / self.sim_s


def server_cpu_s(world: armfleet.World) -> float:
    """CPU time used so far by the world's viewer server process (0 without one) [s]."""
    if world.viewer is None:
        return 0.0
    try:
        fields = Path(f"/proc/{world.viewer.server_pid}/stat").read_text().rsplit(")", 1)[1]
    except OSError:
        return 0.0
    user, system = fields.split()[11:13]
    return (int(user) + int(system)) / os.sysconf("SC_CLK_TCK")


def timed_run(world: armfleet.World, rng: np.random.Generator, sim_s: float) -> Sample:
    """Run ``sim_s`` simulated seconds flat out, re-targeting every 0.5 s.

    CPU time counts this process, every thread (the server's is counted apart:
    the kernel reports it in 10 ms ticks, too coarse for one run).
    """
    wall = cpu = 0.0
    for _ in range(round(sim_s / 0.5)):
        retarget(world, rng)
        wall_0, cpu_0 = time.perf_counter(), time.process_time()
        world.run(0.5)
        wall += time.perf_counter() - wall_0
        cpu += time.process_time() - cpu_0
    return Sample(sim_s, wall, cpu)


def tick_cost_us(world: armfleet.World, calls: int = 200_000) -> float:
    """Mean cost of ``Viewer.tick`` when no frame is due [us]."""
    viewer = world.viewer
    assert isinstance(viewer, Viewer)
    started = time.perf_counter()
    for _ in range(calls):
        viewer.tick(world)
    return (time.perf_counter() - started) / calls * 1e6


def refresh_ms(world: armfleet.World, rng: np.random.Generator, count: int = 40) -> float:
    """Median wall time of one display update of moving arms, sent and acknowledged [ms].

    ``Viewer.refresh`` does what a due tick does (pose every arm that moved,
    queue the batch) and then waits for the server's reply, so this bounds
    the per-update cost from above.
    """
    viewer = world.viewer
    assert viewer is not None
    times = []
    for _ in range(count):
        retarget(world, rng)
        world.run(0.05)
        started = time.perf_counter()
        viewer.refresh()
        times.append(time.perf_counter() - started)
    return statistics.median(times) * 1e3


def open_page(world: armfleet.World, count: int, screenshot: Path) -> tuple[Any, Any, float]:
    """Open the live page headless; (playwright, page, seconds until every mesh is shown)."""
    from playwright.sync_api import sync_playwright

    assert world.viewer is not None
    playwright = sync_playwright().start()
    browser = playwright.chromium.launch(
        executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_FLAGS
    )
    page = browser.new_page(viewport={"width": 1280, "height": 800})
    started = time.perf_counter()
    page.goto(world.viewer.url)
    expected = {f"arm{i}": PANDA_MESHES for i in range(count)}
    page.wait_for_function(MESHES_LOADED_JS, arg=expected, timeout=600_000)
    elapsed = time.perf_counter() - started
    page.wait_for_function("() => !viewer.needs_render", timeout=60_000)
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(screenshot))
    return playwright, browser, elapsed


def measure(count: int, chunk_s: float | None, repeats: int, use_browser: bool) -> Result:
    print(f"\n== {count} arms")
    off, on = armfleet.World(), armfleet.World(viewer=True)
    try:
        if on.viewer is None:
            raise SystemExit(f"the viewer did not start: {on.viewer_error}")
        spawn_off, spawn_on = grid_spawn(off, count), grid_spawn(on, count)
        rng_off, rng_on = np.random.default_rng(count), np.random.default_rng(count)
        warm_up = timed_run(off, rng_off, 1.0)  # also: caches, allocations
        timed_run(on, rng_on, 1.0)
        if chunk_s is None:  # ~0.5 s of wall time per run, in whole half seconds
            chunk_s = max(1.0, 0.5 * round(warm_up.rtf))
        samples_off, samples_on = [], []
        server_0 = server_cpu_s(on)
        for _ in range(repeats):  # alternate, so that load from elsewhere hits both
            samples_off.append(timed_run(off, rng_off, chunk_s))
            samples_on.append(timed_run(on, rng_on, chunk_s))
        server_per_sim_s = (server_cpu_s(on) - server_0) / (repeats * chunk_s)
        tick_us = tick_cost_us(on)
        update_ms = refresh_ms(on, rng_on)
        full_scene_s: float | None = None
        rtf_page: float | None = None
        if use_browser:
            shot = ARTIFACTS / f"viewer_cost_{count}_arms.png"
            playwright, browser, full_scene_s = open_page(on, count, shot)
            try:
                rtf_page = statistics.median(
                    timed_run(on, rng_on, chunk_s).rtf for _ in range(repeats)
                )
            finally:
                browser.close()
                playwright.stop()
            print(f"   browser: full scene after {full_scene_s:.1f} s; screenshot {shot}")
        median_off = statistics.median(x.rtf for x in samples_off)
        median_on = statistics.median(x.rtf for x in samples_on)
        cpu_off = statistics.median(x.cpu_per_sim_s for x in samples_off)
        cpu_on = statistics.median(x.cpu_per_sim_s for x in samples_on) + server_per_sim_s
        # Each on-run follows its off-run at once: their ratio cancels slow drifts of load.
        pair_ratio = statistics.median(
            b.rtf / a.rtf for a, b in zip(samples_off, samples_on, strict=True)
        )
        result = Result(
            arms=count,
            sim_s_per_run=chunk_s,
            runs=repeats,
            rtf_viewer_off=round(median_off, 3),
            rtf_viewer_on=round(median_on, 3),
            ratio_on_off=round(median_on / median_off, 3),
            ratio_on_off_paired=round(pair_ratio, 3),
            cpu_s_per_sim_s_off=round(cpu_off, 4),
            cpu_s_per_sim_s_on=round(cpu_on, 4),
            cpu_overhead=round(cpu_on / cpu_off - 1.0, 4),
            rtf_viewer_on_page_open=None if rtf_page is None else round(rtf_page, 3),
            full_scene_in_browser_s=None if full_scene_s is None else round(full_scene_s, 2),
            tick_not_due_us=round(tick_us, 3),
            display_update_ms=round(update_ms, 3),
            spawn_s_viewer_off=round(spawn_off, 2),
            spawn_s_viewer_on=round(spawn_on, 2),
        )
        print(f"   RTF off {[round(x.rtf, 2) for x in samples_off]}")
        print(f"   RTF on  {[round(x.rtf, 2) for x in samples_on]}")
        return result
    finally:
        off.close()
        on.close()


def print_table(results: list[Result]) -> None:
    header = (
        f"{'arms':>4} | {'RTF off':>7} | {'RTF on':>7} | {'on/off':>6} | {'paired':>6} | "
        f"{'CPU/sim s off':>13} | "
        f"{'CPU/sim s on':>12} | {'CPU +':>6} | {'RTF on+page':>11} | {'full scene':>10} | "
        f"{'tick':>8} | {'update':>8}"
    )
    print("\n" + header + "\n" + "-" * len(header))
    for r in results:
        page = "-" if r.rtf_viewer_on_page_open is None else f"{r.rtf_viewer_on_page_open:.2f}"
        scene = "-" if r.full_scene_in_browser_s is None else f"{r.full_scene_in_browser_s:.1f} s"
        print(
            f"{r.arms:>4} | {r.rtf_viewer_off:>7.2f} | {r.rtf_viewer_on:>7.2f} | "
            f"{r.ratio_on_off:>6.3f} | {r.ratio_on_off_paired:>6.3f} | "
            f"{r.cpu_s_per_sim_s_off:>11.3f} s | "
            f"{r.cpu_s_per_sim_s_on:>10.3f} s | {r.cpu_overhead:>+6.1%} | {page:>11} | "
            f"{scene:>10} | {r.tick_not_due_us:>5.2f} us | {r.display_update_ms:>5.2f} ms"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", type=int, nargs="+", default=[2, 10])
    parser.add_argument(
        "--chunk", type=float, default=None, help="simulated s per timed run (~0.5 s wall)"
    )
    parser.add_argument("--repeats", type=int, default=15, help="timed runs per mode")
    parser.add_argument("--no-browser", action="store_true", help="skip the headless page")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    use_browser = CHROMIUM.exists() and not args.no_browser
    if not use_browser:
        print(f"no browser measurements ({CHROMIUM} missing or --no-browser)")
    results = [measure(n, args.chunk, args.repeats, use_browser) for n in args.arms]
    print_table(results)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average_1_5_15_min_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "display_rate_hz": armfleet.viewer.DISPLAY_RATE_HZ,
        "results": [asdict(r) for r in results],
    }
    RESULTS.write_text(json.dumps(report, indent=2) + "\n")
    print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
