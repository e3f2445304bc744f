"""Options shared by the commands that run a world (``spawn``, ``launch``)."""

from __future__ import annotations

import argparse
import math

from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.record_option import HELP, METAVAR, check_record_path


def add_run_arguments(parser: OneLineParser) -> None:
    parser.add_argument(
        "--duration", type=float, default=None, metavar="S",
        help="simulated seconds to run, then exit (default: until Ctrl-C)",
    )  # fmt: skip
    pacing = parser.add_mutually_exclusive_group()
    pacing.add_argument(
        "--realtime", dest="realtime", action="store_const", const=True, default=None,
        help="pace the simulation to the wall clock (default)",
    )  # fmt: skip
    pacing.add_argument(
        "--fast", dest="realtime", action="store_const", const=False,
        help="run as fast as possible",
    )  # fmt: skip
    parser.add_argument("--no-viewer", action="store_true", help="run headless")
    parser.add_argument(
        "--viewer-port", type=int, default=None, metavar="PORT",
        help="web port of the viewer (default: a free port)",
    )  # fmt: skip
    parser.add_argument("--record", metavar=METAVAR, default=None, help=HELP)
    parser.add_argument("--quiet", action="store_true", help="no progress or status lines")


def check_run_arguments(args: argparse.Namespace) -> None:
    """Raise :class:`UsageError` for run options that make no sense."""
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration >= 0):
        raise UsageError(f"--duration {args.duration} is invalid; give seconds >= 0")
    check_record_path(args.record)
    if args.viewer_port is not None and not 1 <= args.viewer_port <= 65535:
        raise UsageError(f"--viewer-port {args.viewer_port} is invalid; give 1-65535")
