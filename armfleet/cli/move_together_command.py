"""``armfleet move-together bob=Q1,Q2,... toby=Q1,Q2,... [--wait] [--avoid-collisions
[--clearance M] [--planning-timeout S]]``: several arms that start on the same step and
finish at the same instant, each in a straight line or planned jointly around each other
and everything else."""

from __future__ import annotations

import argparse

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.number_arguments import wait_timeout
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.planning_arguments import add_planning_arguments, planning_keywords
from armfleet.remote.remote_arm import WAIT_TIMEOUT_S

TARGET_SYNTAX = "NAME=Q1,Q2,..."


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(
        subparsers,
        "move-together",
        "move several arms of the running world so that they finish at the same instant",
    )
    parser.add_argument(
        "targets", nargs="+", metavar=TARGET_SYNTAX,
        help="per arm, its name, '=' and its target joint positions, base to tool, separated "
        "by commas, no spaces [rad or m], e.g. bob=0,-0.8,0,-2.4,0,1.6,0.8",
    )  # fmt: skip
    add_planning_arguments(parser, what="the arms, planned jointly,")
    parser.add_argument("--wait", action="store_true", help="return once every arm holds")
    parser.add_argument(
        "--wait-timeout", type=wait_timeout, default=WAIT_TIMEOUT_S, metavar="S",
        help=f"longest wait per arm with --wait [s] (default {WAIT_TIMEOUT_S:g})",
    )  # fmt: skip
    parser.set_defaults(run=run)


def parse_targets(texts: list[str]) -> dict[str, list[float]]:
    """``["bob=0,0.1", "toby=..."]`` as ``{"bob": [0.0, 0.1], ...}``."""
    targets: dict[str, list[float]] = {}
    for text in texts:
        name, equals, values = text.partition("=")
        if not equals or not name or not values:
            raise UsageError(f"target {text!r} is malformed; give {TARGET_SYNTAX}, one per arm")
        if name in targets:
            raise UsageError(f"arm {name!r} is given twice; give one {TARGET_SYNTAX} per arm")
        try:
            targets[name] = [float(v) for v in values.split(",")]
        except ValueError:
            raise UsageError(
                f"target {text!r}: {values!r} is not numbers separated by commas; give "
                f"{TARGET_SYNTAX} [rad or m]"
            ) from None
    return targets


def run(args: argparse.Namespace) -> int:
    targets = parse_targets(args.targets)
    planning = planning_keywords(args)
    names = ", ".join(targets)
    with connect_from(args) as client:
        duration = client.move_together(targets, **planning)
        if not args.wait:
            how = " around obstacles" if planning else ""
            print(f"{names}: moving together{how}, {duration:.3f} s")
            return 0
        stamps = [client.arm(name).wait(args.wait_timeout).stamp for name in targets]
    print(f"{names}: moved together in {duration:.3f} s; holding at t={max(stamps):.3f}s")
    return 0
