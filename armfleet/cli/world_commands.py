"""``armfleet info``, ``pause``, ``resume`` and ``step``: the running world as a whole."""

from __future__ import annotations

import argparse

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.number_arguments import step_count
from armfleet.cli.parser import OneLineParser


def add_parsers(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    add_remote_command(
        subparsers, "info", "time, step, real-time factor and arms of the running world"
    ).set_defaults(run=info)
    add_remote_command(
        subparsers, "pause", "pause the running world (it still answers)"
    ).set_defaults(run=pause)
    add_remote_command(subparsers, "resume", "resume the paused world").set_defaults(run=resume)
    step = add_remote_command(subparsers, "step", "advance the paused world by a few steps")
    step.add_argument(
        "count", nargs="?", type=step_count, default=1, metavar="N", help="steps (default 1)"
    )
    step.set_defaults(run=step_world)


def info(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        world = client.info()
    rtf = "-" if world.realtime_factor is None else f"{world.realtime_factor:.2f}"
    print(f"time:      {world.time_s:.3f} s")
    print(f"dt:        {world.dt_s:g} s")
    print(f"rtf:       {rtf}")
    print(f"state:     {'paused' if world.paused else 'running'}")
    print(f"arms:      {', '.join(world.arms) or '(none)'}")
    print(f"api:       {world.address} (process {world.pid}, armfleet {world.version})")
    print(f"streams:   {world.streams} client(s), {world.subscriptions} subscription(s)")
    return 0


def pause(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        print(f"paused at t={client.pause():.3f}s")
    return 0


def resume(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        print(f"resumed at t={client.resume():.3f}s")
    return 0


def step_world(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        print(f"t={client.step(args.count):.3f}s")
    return 0
