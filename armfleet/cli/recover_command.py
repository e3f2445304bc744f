"""``armfleet recover RUN.mcap [-o OUT.mcap]``: a complete, indexed copy of a recording
whose writer died (see :mod:`armfleet.recording.recover`)."""

from __future__ import annotations

import argparse

from armfleet.cli.parser import OneLineParser
from armfleet.cli.path_arguments import path_text
from armfleet.recording.recover import recover


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "recover",
        help="write a complete, indexed copy of a recording whose writer died (kill -9)",
        description="Read RUN.mcap from the start and write every whole record (schemas, "
        "channels, messages, attachments, metadata) into a new MCAP file with its index and "
        "summary, as the mcap CLI's recover does. A recording cut short by kill -9 or a crash "
        "has no summary: most MCAP readers then find no messages in it. RUN.mcap is only read.",
    )
    parser.add_argument(
        "recording", type=path_text, metavar="RUN.mcap", help="the recording to recover"
    )
    parser.add_argument(
        "-o", "--output", type=path_text, default=None, metavar="OUT.mcap",
        help="the file to write (default: RUN-recovered.mcap beside RUN.mcap; must not exist)",
    )  # fmt: skip
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    print(recover(args.recording, args.output).describe())
    return 0
