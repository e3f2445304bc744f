"""Options shared by the commands that run a world (``spawn``, ``launch``)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from armfleet.cli.foxglove_options import add_foxglove_arguments, check_foxglove_arguments
from armfleet.cli.number_arguments import port, run_duration
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.path_arguments import path_text
from armfleet.cli.record_option import HELP, METAVAR, check_record_path
from armfleet.cli.ros_options import add_ros_arguments, check_ros_arguments
from armfleet.description.package_finder import PACKAGE_PATH_ENV


def add_run_arguments(parser: OneLineParser) -> None:
    parser.add_argument(
        "--duration", type=run_duration, default=None, metavar="S",
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
        "--viewer-port", type=port, default=None, metavar="PORT",
        help="web port of the viewer (default: a free port)",
    )  # fmt: skip
    parser.add_argument("--record", type=path_text, metavar=METAVAR, default=None, help=HELP)
    parser.add_argument("--quiet", action="store_true", help="no progress or status lines")
    parser.add_argument(
        "--package-path", action="append", default=[], metavar="DIR", type=path_text,
        help="a folder of ROS packages (or a package) for the model files' package:// and "
        "$(find) (repeatable; searched before ARMFLEET_PACKAGE_PATH and ROS_PACKAGE_PATH)",
    )  # fmt: skip
    add_foxglove_arguments(parser)
    add_ros_arguments(parser)


def check_run_arguments(args: argparse.Namespace) -> None:
    """Raise :class:`UsageError` for run options that make no sense (the numbers were
    checked while parsing)."""
    check_record_path(args.record)
    check_foxglove_arguments(args)
    check_ros_arguments(args)
    use_package_paths(args.package_path)


def use_package_paths(folders: list[str]) -> None:
    """Put ``--package-path`` folders first on ``ARMFLEET_PACKAGE_PATH`` for this process,
    the one that reads the model files (this command's world)."""
    missing = [folder for folder in folders if not Path(folder).expanduser().is_dir()]
    if missing:
        raise UsageError(f"--package-path {missing[0]}: not a folder; give a folder of packages")
    if folders:
        given = [str(Path(folder).expanduser().absolute()) for folder in folders]
        before = os.environ.get(PACKAGE_PATH_ENV)
        os.environ[PACKAGE_PATH_ENV] = os.pathsep.join([*given, *([before] if before else [])])
