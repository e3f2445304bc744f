"""``armfleet remove NAME``: take an arm out of the running world."""

from __future__ import annotations

import argparse

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.parser import OneLineParser


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(subparsers, "remove", "take an arm out of the running world")
    parser.add_argument("names", nargs="+", metavar="NAME", help="arm names")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        for name in args.names:
            client.remove(name)
            print(f"{name}: removed")
    return 0
