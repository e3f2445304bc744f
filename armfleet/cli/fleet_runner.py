"""Run a :class:`FleetSpec` from the command line: bring-up lines, status, clean shutdown."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from collections.abc import Callable
from types import FrameType

from armfleet.cli.status_line import status_line
from armfleet.launch import launch
from armfleet.messages import BringupEvent
from armfleet.spec import FleetSpec
from armfleet.world import World

STATUS_PERIOD_S = 1.0
CHUNK_S = 0.02


def run_fleet(spec: FleetSpec, args: argparse.Namespace) -> int:
    """Bring the spec's arms up, run until ``--duration`` or Ctrl-C/SIGTERM, close cleanly."""
    viewer = (spec.world.viewer and not args.no_viewer) or args.record is not None
    realtime = spec.world.realtime if args.realtime is None else args.realtime

    def say(line: str) -> None:
        if not args.quiet:
            print(line, flush=True)

    def on_term(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)  # SIGTERM shuts down like Ctrl-C

    def before_spawn(world: World) -> None:
        if viewer:
            if world.viewer is not None:
                print(f"viewer: {world.viewer.url}", flush=True)
            else:
                print(f"armfleet: viewer not started: {world.viewer_error}", file=sys.stderr)

        def on_bringup(event: BringupEvent) -> None:
            say(f"[{event.arm}] {event.stage.value} (t={event.stamp:.3f}s, {event.wall_time:.2f}s)")

        world.bus.subscribe("/bringup", on_bringup)

    try:
        started = time.perf_counter()
        world = launch(spec, viewer=viewer, viewer_port=args.viewer_port, before_spawn=before_spawn)
        try:
            say(f"{len(spec.arms)} arm(s) ready in {time.perf_counter() - started:.2f}s")
            _run(world, args.duration, realtime, say)
        finally:
            if args.record is not None and world.viewer is not None:
                world.viewer.save(args.record)
                say(f"replay saved to {args.record}")
            world.close()
    except KeyboardInterrupt:
        say("interrupted; shut down cleanly")
    return 0


def _run(world: World, duration: float | None, realtime: bool, say: Callable[[str], None]) -> None:
    start_sim, start_wall = world.time, time.perf_counter()
    next_status = start_wall + STATUS_PERIOD_S
    while duration is None or world.time - start_sim < duration - 1e-9:
        chunk = CHUNK_S if duration is None else min(CHUNK_S, duration - (world.time - start_sim))
        world.run(chunk)
        now = time.perf_counter()
        elapsed_sim = world.time - start_sim
        if realtime and elapsed_sim > now - start_wall:
            time.sleep(elapsed_sim - (now - start_wall))
            now = time.perf_counter()
        if now >= next_status:
            say(status_line(world, elapsed_sim / max(now - start_wall, 1e-9)))
            next_status = now + STATUS_PERIOD_S
