"""``armfleet spawn``: bring arms up one at a time in a new world and run it."""

from __future__ import annotations

import argparse
import math
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from types import FrameType

from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.status_line import status_line
from armfleet.description import ModelLibrary
from armfleet.errors import UnknownModel
from armfleet.messages import BringupEvent
from armfleet.names import check_arm_name
from armfleet.spawn_pose import AT_SYNTAX, SpawnPose
from armfleet.world import World

STATUS_PERIOD_S = 1.0
CHUNK_S = 0.02


@dataclass(frozen=True)
class ArmRequest:
    name: str
    model: str
    pose: SpawnPose


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "spawn",
        help="bring arms up one at a time in a new world and run it",
        description="Bring arms up one at a time in one PyBullet world and run it "
        "until --duration or Ctrl-C.",
    )
    parser.add_argument("names", nargs="+", metavar="NAME", help="arm names, e.g. bob toby")
    parser.add_argument(
        "--at",
        nargs="+",
        metavar=AT_SYNTAX,
        required=True,
        help="spawn pose per name, in order [m, m, m, deg], e.g. --at 0,0 1,0,0,180",
    )
    parser.add_argument(
        "--model",
        nargs="+",
        default=["panda"],
        metavar="MODEL",
        help="one model for all arms or one per name (default: panda; see 'armfleet models')",
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        metavar="S",
        help="simulated seconds to run, then exit (default: until Ctrl-C)",
    )
    pacing = parser.add_mutually_exclusive_group()
    pacing.add_argument(
        "--realtime",
        dest="realtime",
        action="store_true",
        default=True,
        help="pace the simulation to the wall clock (default)",
    )
    pacing.add_argument(
        "--fast", dest="realtime", action="store_false", help="run as fast as possible"
    )
    parser.add_argument("--no-viewer", action="store_true", help="run headless")
    parser.add_argument(
        "--viewer-port",
        type=int,
        default=None,
        metavar="PORT",
        help="web port of the viewer (default: a free port)",
    )
    parser.add_argument(
        "--record",
        metavar="RUN.html",
        default=None,
        help="save a standalone HTML replay of the run at exit",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress or status lines")
    parser.set_defaults(run=run)


def parse_requests(args: argparse.Namespace, models: ModelLibrary) -> list[ArmRequest]:
    """Check every argument before anything starts; raise UsageError or ArmfleetError."""
    names: list[str] = args.names
    if len(args.at) != len(names):
        raise UsageError(
            f"got {len(names)} names but {len(args.at)} --at poses; give one --at "
            f"{AT_SYNTAX} per name, in order"
        )
    if len(args.model) not in (1, len(names)):
        raise UsageError(
            f"got {len(args.model)} --model values for {len(names)} names; give one for all "
            "or one per name"
        )
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration >= 0):
        raise UsageError(f"--duration {args.duration} is invalid; give seconds >= 0")
    if args.record is not None and not args.record.endswith(".html"):
        raise UsageError(f"--record {args.record} must name an .html file")
    available = models.names
    chosen = args.model * len(names) if len(args.model) == 1 else args.model
    requests: list[ArmRequest] = []
    for name, model, at in zip(names, chosen, args.at, strict=True):
        check_arm_name(name, [r.name for r in requests])
        if model not in available:
            raise UnknownModel(model, available)
        requests.append(ArmRequest(name, model, SpawnPose.parse(at)))
    return requests


def run(args: argparse.Namespace) -> int:
    models = ModelLibrary()
    requests = parse_requests(args, models)
    viewer = not args.no_viewer or args.record is not None

    def say(line: str) -> None:
        if not args.quiet:
            print(line, flush=True)

    # SIGTERM ends the run like Ctrl-C: the world (and its viewer) close cleanly.
    def on_term(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)
    world = World(models=models, viewer=viewer, viewer_port=args.viewer_port)
    try:
        if viewer:
            if world.viewer is not None:
                print(f"viewer: {world.viewer.url}", flush=True)
            else:
                print(f"armfleet: viewer not started: {world.viewer_error}", file=sys.stderr)

        def on_bringup(event: BringupEvent) -> None:
            say(f"[{event.arm}] {event.stage.value} (t={event.stamp:.3f}s, {event.wall_time:.2f}s)")

        world.bus.subscribe("/bringup", on_bringup)
        started = time.perf_counter()
        for request in requests:
            world.spawn(request.name, request.model, request.pose)
        say(f"{len(requests)} arm(s) ready in {time.perf_counter() - started:.2f}s")
        _run_world(world, args.duration, args.realtime, say)
    except KeyboardInterrupt:
        say("interrupted; shutting down")
    finally:
        if args.record is not None and world.viewer is not None:
            world.viewer.save(args.record)
            say(f"replay saved to {args.record}")
        world.close()
    return 0


def _run_world(
    world: World, duration: float | None, realtime: bool, say: Callable[[str], None]
) -> None:
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
