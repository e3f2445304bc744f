"""Entry point of the ``armfleet`` command."""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
from collections.abc import Sequence

from armfleet._version import __version__
from armfleet.cli.parser import OneLineParser, UsageError, fail
from armfleet.errors import ArmfleetError

#: Each command and the modules of :mod:`armfleet.cli` that add its parser, in the order
#: ``armfleet --help`` lists them. Only the named command's modules are imported, so a
#: command loads what it needs and no more (``armfleet arms`` neither Pinocchio nor
#: matplotlib); ``tests/test_cli_startup.py`` checks this table against the modules.
COMMANDS: dict[str, tuple[str, ...]] = {
    "spawn": ("spawn_command",),
    "launch": ("launch_command",),
    "models": ("models_command",),
    "check-model": ("check_model_command",),
    "arms": ("arms_command",),
    "move": ("move_command",),
    "move-together": ("move_together_command",),
    "grip": ("grip_command",),
    "remove": ("remove_command",),
    "reset": ("reset_command",),
    "topic": ("topic_command",),
    "objects": ("object_commands",),
    "add-object": ("object_commands",),
    "remove-object": ("object_commands",),
    "info": ("world_commands", "recording_info_command"),
    "pause": ("world_commands",),
    "resume": ("world_commands",),
    "step": ("world_commands",),
    "plot": ("plot_command",),
    "replay": ("replay_command",),
    "recover": ("recover_command",),
    "sweep": ("sweep_command",),
    "sweep-report": ("sweep_report_command",),
}
#: Every command that starts a world serves the live API.
WORLD_COMMANDS = ("spawn", "launch")


def build_parser(command: str | None = None) -> OneLineParser:
    """The ``armfleet`` parser: with every command, or only with ``command``'s (the one
    about to run; its modules alone are imported)."""
    parser = OneLineParser(prog="armfleet", description="Several robot arms in one PyBullet world.")
    parser.add_argument("--version", action="version", version=f"armfleet {__version__}")
    # No metavar: a missing or unknown command then names the valid ones.
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=OneLineParser)
    wanted = list(COMMANDS) if command is None else [command]
    added: set[str] = set()
    for name in wanted:
        for module_name in COMMANDS[name]:
            if module_name not in added:
                added.add(module_name)
                _add_parsers(module_name, subparsers)
    for name in WORLD_COMMANDS:
        if name in subparsers.choices:
            from armfleet.cli.api_options import add_api_arguments

            add_api_arguments(subparsers.choices[name])
    parser.commands = tuple(COMMANDS)
    return parser


def _add_parsers(module_name: str, subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    module = importlib.import_module(f"armfleet.cli.{module_name}")
    if module_name == "recording_info_command":  # it extends the info command's parser
        module.extend_info_parser(subparsers.choices["info"])
    elif hasattr(module, "add_parsers"):
        module.add_parsers(subparsers)
    else:
        module.add_parser(subparsers)


def _command_of(args: Sequence[str]) -> str | None:
    """The command named in ``args`` when it is a known one; None for an option first
    (``--help``, ``--version``), no command or an unknown one (then the whole parser is
    built, to list the commands)."""
    if not args or args[0].startswith("-"):
        return None
    return args[0] if args[0] in COMMANDS else None


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; a user error is one line on stderr and exit code 2."""
    logging.basicConfig(level=logging.WARNING, format="armfleet: %(message)s")
    try:
        args_given = sys.argv[1:] if argv is None else list(argv)
        if args_given == ["--version"]:  # no command's parser needed
            print(f"armfleet {__version__}")
            return 0
        parser = build_parser(_command_of(args_given))
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
