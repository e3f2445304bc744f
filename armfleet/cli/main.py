"""Entry point of the ``armfleet`` command."""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Sequence

from armfleet._version import __version__
from armfleet.cli import (
    arms_command,
    check_model_command,
    grip_command,
    launch_command,
    models_command,
    move_command,
    move_together_command,
    object_commands,
    plot_command,
    recording_info_command,
    recover_command,
    remove_command,
    replay_command,
    reset_command,
    spawn_command,
    sweep_command,
    sweep_report_command,
    topic_command,
    world_commands,
)
from armfleet.cli.api_options import add_api_arguments
from armfleet.cli.parser import OneLineParser, UsageError, fail
from armfleet.errors import ArmfleetError


def build_parser() -> OneLineParser:
    parser = OneLineParser(prog="armfleet", description="Several robot arms in one PyBullet world.")
    parser.add_argument("--version", action="version", version=f"armfleet {__version__}")
    # No metavar: a missing or unknown command then names the valid ones.
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=OneLineParser)
    spawn_command.add_parser(subparsers)
    launch_command.add_parser(subparsers)
    # Every command that starts a world serves the live API.
    for command in ("spawn", "launch"):
        add_api_arguments(subparsers.choices[command])
    models_command.add_parser(subparsers)
    check_model_command.add_parser(subparsers)
    arms_command.add_parser(subparsers)
    move_command.add_parser(subparsers)
    move_together_command.add_parser(subparsers)
    grip_command.add_parser(subparsers)
    remove_command.add_parser(subparsers)
    reset_command.add_parser(subparsers)
    topic_command.add_parser(subparsers)
    object_commands.add_parsers(subparsers)
    world_commands.add_parsers(subparsers)
    recording_info_command.extend_info_parser(subparsers.choices["info"])
    plot_command.add_parser(subparsers)
    replay_command.add_parser(subparsers)
    recover_command.add_parser(subparsers)
    sweep_command.add_parser(subparsers)
    sweep_report_command.add_parser(subparsers)
    parser.commands = tuple(subparsers.choices)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; a user error is one line on stderr and exit code 2."""
    logging.basicConfig(level=logging.WARNING, format="armfleet: %(message)s")
    try:
        parser = build_parser()
        args_given = sys.argv[1:] if argv is None else list(argv)
        if not args_given:
            raise UsageError(
                f"no command given; choose one of: {', '.join(parser.commands)} "
                "(see 'armfleet --help')"
            )
        args = parser.parse_args(args_given)
        code: int = args.run(args)
        return code
    except (UsageError, ArmfleetError) as exc:
        fail(str(exc))
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # output piped into e.g. head, which has had enough
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
