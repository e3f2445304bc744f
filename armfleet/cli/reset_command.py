"""``armfleet reset NAME...``: clear an arm's protective stop (or, with --error, its fault)."""

from __future__ import annotations

import argparse

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.parser import OneLineParser


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(
        subparsers, "reset", "let a stopped arm of the running world move again"
    )
    parser.add_argument("names", nargs="+", metavar="NAME", help="arm names")
    parser.add_argument(
        "--error",
        action="store_true",
        help="also leave 'error' (restart its controllers at the current pose)",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        for name in args.names:
            arm = client.arm(name)
            if args.error:
                arm.reset()
            else:
                arm.reset_stop()
            print(f"{name}: reset")
    return 0
