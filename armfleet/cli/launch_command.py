"""``armfleet launch SPEC``: bring up the world a launch spec describes (or just check it)."""

from __future__ import annotations

import argparse

from armfleet.cli.fleet_runner import run_fleet
from armfleet.cli.parser import OneLineParser
from armfleet.cli.path_arguments import path_text
from armfleet.cli.run_options import add_run_arguments, check_run_arguments
from armfleet.spec import load_spec


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "launch",
        help="bring up the world of a launch spec (YAML)",
        description="Bring up the world a launch spec describes, one arm at a time. SPEC is "
        "a file, or the name of a shipped spec (e.g. bob_and_toby).",
    )
    parser.add_argument(
        "spec", type=path_text, metavar="SPEC", help="launch spec file or shipped spec name"
    )
    parser.add_argument(
        "--check", action="store_true", help="validate the spec and exit without running"
    )
    add_run_arguments(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    check_run_arguments(args)
    spec = load_spec(args.spec)
    if args.check:
        models = sorted({arm.model for arm in spec.arms})
        print(
            f"{spec.source}: ok: {len(spec.arms)} arm(s) ({', '.join(models) or 'none'}), "
            f"dt {spec.world.dt_s:g} s"
        )
        return 0
    return run_fleet(spec, args)
