"""What the MeshCat viewer costs the simulation, and how fast a browser shows the scene.

For 2 and 10 Pandas (a grid 1 m apart, random targets inside the joint
limits) this runs the same workload flat out in two worlds of one process,
one without and one with a viewer, alternating chunks of simulated time, and
reports the real-time factor (simulated time / wall time) of each and their
ratio. With Debian's Chromium at /usr/bin/chromium it also opens the live page
headless and reports the time until every mesh of every arm is in the scene,
and the real-time factor while that page is open (the browser then competes
for the same CPU). Results go to ``benchmarks/results/viewer_cost.json``;
screenshots to ``test-artifacts/``.

Run: ``python benchmarks/viewer_cost.py [--arms 2 10] [--chunk 1.0] [--repeats 5]``
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import platform
import statistics
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

import armfleet
import armfleet.viewer

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "viewer_cost.json"
ARTIFACTS = ROOT / "test-artifacts"
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_FLAGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
)
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
    rtf_viewer_off: float
    rtf_viewer_on: float
    ratio_on_off: float
    rtf_viewer_on_page_open: float | None
    full_scene_in_browser_s: float | None
    tick_not_due_us: float
    spawn_s_viewer_off: float
    spawn_s_viewer_on: float


def grid_spawn(world: armfleet.World, count: int) -> float:
    """Spawn ``count`` Pandas on a 1 m grid; returns the wall time it took [s]."""
    columns = math.ceil(math.sqrt(count))
    started = time.perf_counter()
    for i in range(count):
        world.spawn(f"arm{i}", at=(float(i % columns), float(i // columns)))
    return time.perf_counter() - started


def retarget(world: armfleet.World, rng: np.random.Generator) -> None:
    """Give every arm at rest a random target within 0.6 rad of home and the joint limits.

    Neighbours 1 m apart can still touch; an arm in protective stop is reset
    and sent home.
    """
    for arm in world.arms.values():
        if arm.is_moving:
            continue
        home = np.array(arm.description.home)
        lower, upper = arm.joint_limits
        target = np.clip(home + rng.uniform(-0.6, 0.6, size=len(home)), lower, upper)
        try:
            arm.move_to(target)
        except armfleet.ArmfleetError:  # protective stop after touching a neighbour
            arm.reset()
            arm.move_to(home)


def timed_run(world: armfleet.World, rng: np.random.Generator, sim_s: float) -> float:
    """Run ``sim_s`` simulated seconds flat out, re-targeting every 0.5 s; the wall time [s]."""
    wall = 0.0
    steps = round(sim_s / 0.5)
    for _ in range(steps):
        retarget(world, rng)
        started = time.perf_counter()
        world.run(0.5)
        wall += time.perf_counter() - started
    return wall


def tick_cost_us(world: armfleet.World, calls: int = 200_000) -> float:
    """Mean cost of ``Viewer.tick`` when no frame is due [us]."""
    viewer = world.viewer
    assert viewer is not None
    started = time.perf_counter()
    for _ in range(calls):
        viewer.tick(world)
    return (time.perf_counter() - started) / calls * 1e6


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


def measure(count: int, chunk_s: float, repeats: int, use_browser: bool) -> Result:
    print(f"\n== {count} arms")
    off, on = armfleet.World(), armfleet.World(viewer=True)
    try:
        if on.viewer is None:
            raise SystemExit(f"the viewer did not start: {on.viewer_error}")
        spawn_off, spawn_on = grid_spawn(off, count), grid_spawn(on, count)
        rng_off, rng_on = np.random.default_rng(count), np.random.default_rng(count)
        timed_run(off, rng_off, 1.0)  # warm-up: caches, allocations
        timed_run(on, rng_on, 1.0)
        rtf_off, rtf_on = [], []
        for _ in range(repeats):
            rtf_off.append(chunk_s / timed_run(off, rng_off, chunk_s))
            rtf_on.append(chunk_s / timed_run(on, rng_on, chunk_s))
        tick_us = tick_cost_us(on)
        full_scene_s: float | None = None
        rtf_page: float | None = None
        if use_browser:
            shot = ARTIFACTS / f"viewer_cost_{count}_arms.png"
            playwright, browser, full_scene_s = open_page(on, count, shot)
            try:
                rtf_page = statistics.median(
                    chunk_s / timed_run(on, rng_on, chunk_s) for _ in range(repeats)
                )
            finally:
                browser.close()
                playwright.stop()
            print(f"   browser: full scene after {full_scene_s:.1f} s; screenshot {shot}")
        median_off, median_on = statistics.median(rtf_off), statistics.median(rtf_on)
        result = Result(
            arms=count,
            sim_s_per_run=chunk_s,
            rtf_viewer_off=round(median_off, 3),
            rtf_viewer_on=round(median_on, 3),
            ratio_on_off=round(median_on / median_off, 3),
            rtf_viewer_on_page_open=None if rtf_page is None else round(rtf_page, 3),
            full_scene_in_browser_s=None if full_scene_s is None else round(full_scene_s, 2),
            tick_not_due_us=round(tick_us, 3),
            spawn_s_viewer_off=round(spawn_off, 2),
            spawn_s_viewer_on=round(spawn_on, 2),
        )
        print(f"   RTF off {rtf_off}\n   RTF on  {rtf_on}")
        return result
    finally:
        off.close()
        on.close()


def print_table(results: list[Result]) -> None:
    header = (
        f"{'arms':>4} | {'RTF off':>8} | {'RTF on':>8} | {'on/off':>6} | "
        f"{'RTF on+page':>11} | {'full scene':>10} | {'tick':>8}"
    )
    print("\n" + header + "\n" + "-" * len(header))
    for r in results:
        page = "-" if r.rtf_viewer_on_page_open is None else f"{r.rtf_viewer_on_page_open:.2f}"
        scene = "-" if r.full_scene_in_browser_s is None else f"{r.full_scene_in_browser_s:.1f} s"
        print(
            f"{r.arms:>4} | {r.rtf_viewer_off:>8.2f} | {r.rtf_viewer_on:>8.2f} | "
            f"{r.ratio_on_off:>6.3f} | {page:>11} | {scene:>10} | {r.tick_not_due_us:>5.2f} us"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", type=int, nargs="+", default=[2, 10])
    parser.add_argument("--chunk", type=float, default=2.0, help="simulated s per timed run")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per mode")
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
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "display_rate_hz": armfleet.viewer.DISPLAY_RATE_HZ,
        "results": [asdict(r) for r in results],
    }
    RESULTS.write_text(json.dumps(report, indent=2) + "\n")
    print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
