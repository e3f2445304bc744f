"""``armfleet move NAME --joints q1 q2 ... [--wait]``: send an arm to joint positions."""

from __future__ import annotations

import argparse

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.parser import OneLineParser
from armfleet.remote.remote_arm import WAIT_TIMEOUT_S


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(
        subparsers, "move", "send an arm of the running world to joint positions"
    )
    parser.add_argument("name", metavar="NAME", help="arm name (see 'armfleet arms')")
    parser.add_argument(
        "--joints", nargs="+", type=float, required=True, metavar="Q",
        help="target position per joint, base to tool [rad or m]",
    )  # fmt: skip
    parser.add_argument("--wait", action="store_true", help="return once the arm holds the target")
    parser.add_argument(
        "--wait-timeout", type=float, default=WAIT_TIMEOUT_S, metavar="S",
        help=f"longest wait for the motion with --wait [s] (default {WAIT_TIMEOUT_S:g})",
    )  # fmt: skip
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        arm = client.arm(args.name)
        arm.move_to(args.joints)
        target = " ".join(f"{v:+.3f}" for v in args.joints)
        if not args.wait:
            print(f"{arm.name}: moving to [{target}]")
            return 0
        state = arm.wait(args.wait_timeout)
        print(f"{arm.name}: holding [{target}] at t={state.stamp:.3f}s")
    return 0
