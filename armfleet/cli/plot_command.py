"""``armfleet plot RUN.mcap [--arm NAME ...] [-o OUT.png]``: tracking plots of a recording."""

from __future__ import annotations

import argparse
import re
import sys

from armfleet.checks.names import ARM_NAME_PATTERN
from armfleet.cli.misplaced_values import ValueTest
from armfleet.cli.parser import OneLineParser
from armfleet.cli.path_arguments import path_text


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "plot",
        help="plot reference vs measured joints and the tracking error of a recording",
        description="Plot, per joint, the position controller's reference against the measured "
        "position and the tracking error, one figure per arm, from the "
        "/<arm>/position_controller/state messages of a recording (armfleet spawn/launch "
        "--record RUN.mcap).",
    )
    parser.add_argument("recording", type=path_text, metavar="RUN.mcap", help="the recording")
    parser.add_argument(
        "--arm", nargs="+", default=None, metavar="NAME",
        help="arms to plot (default: every arm with a recorded controller state)",
    )  # fmt: skip
    parser.add_argument(
        "-o", "--output", type=path_text, default=None, metavar="OUT.png",
        help="figure file (.png, .svg or .pdf; with several arms, <OUT>_<arm>.png), or an "
        "existing folder (default: <RUN>_<arm>.png beside the recording)",
    )  # fmt: skip
    parser.set_defaults(run=run)
    # A recording typed after --arm ends up there: what is not an arm name was meant as it.
    parser.value_tests["--arm"] = ValueTest(
        "arm name", lambda text: re.match(ARM_NAME_PATTERN, text) is not None
    )


def run(args: argparse.Namespace) -> int:
    if sys.stderr.isatty():  # a sign of life: matplotlib and the reading take seconds
        print(f"plotting {args.recording}...", file=sys.stderr, flush=True)
    # The recording reader and matplotlib load only for this command.
    from armfleet.recording import open_recording, plot_recording

    recording = open_recording(args.recording)
    paths = plot_recording(recording, args.arm, args.output)
    for arm, path in paths.items():
        print(f"{arm}: {path}")
    return 0
