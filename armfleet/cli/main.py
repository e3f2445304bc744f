"""Entry point of the ``armfleet`` command."""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence

from armfleet import __version__
from armfleet.cli import launch_command, models_command, spawn_command
from armfleet.cli.parser import OneLineParser, UsageError, fail
from armfleet.errors import ArmfleetError


def build_parser() -> OneLineParser:
    parser = OneLineParser(prog="armfleet", description="Several robot arms in one PyBullet world.")
    parser.add_argument("--version", action="version", version=f"armfleet {__version__}")
    subparsers = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=OneLineParser
    )
    spawn_command.add_parser(subparsers)
    launch_command.add_parser(subparsers)
    models_command.add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; a user error is one line on stderr and exit code 2."""
    logging.basicConfig(level=logging.WARNING, format="armfleet: %(message)s")
    try:
        args = build_parser().parse_args(argv)
        code: int = args.run(args)
        return code
    except (UsageError, ArmfleetError) as exc:
        fail(str(exc))
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
