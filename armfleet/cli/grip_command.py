"""``armfleet grip NAME open|close|WIDTH_M [--force N] [--wait]``: drive an arm's fingers."""

from __future__ import annotations

import argparse

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.number_arguments import wait_timeout
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.messages import GripperState
from armfleet.remote.remote_gripper import GRIP_WAIT_TIMEOUT_S


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(
        subparsers, "grip", "open or close the gripper of an arm of the running world"
    )
    parser.add_argument("name", metavar="NAME", help="arm name (a model with fingers, e.g. panda)")
    parser.add_argument(
        "action", metavar="open|close|WIDTH_M",
        help="open fully; close until blocked, then squeeze with --force; or go to a width [m; "
        "rad for a revolute jaw]",
    )  # fmt: skip
    parser.add_argument(
        "--force", type=float, default=None, metavar="N",
        help="force limit per finger [N; N m for a revolute jaw] (the grasp force when closing; "
        "default: the arm's grasp force)",
    )  # fmt: skip
    parser.add_argument(
        "--wait", action="store_true",
        help="return once the fingers stop; print width, mode and whether they hold something",
    )  # fmt: skip
    parser.add_argument(
        "--wait-timeout", type=wait_timeout, default=GRIP_WAIT_TIMEOUT_S, metavar="S",
        help=f"longest wait with --wait [s] (default {GRIP_WAIT_TIMEOUT_S:g})",
    )  # fmt: skip
    parser.set_defaults(run=run)


def parse_action(text: str) -> float | str:
    """``open``, ``close``, or a width [m] (its range is the world's to check)."""
    if text in ("open", "close"):
        return text
    try:
        width = float(text)
    except ValueError:
        raise UsageError(
            f"grip action {text!r} is invalid; give open, close or a width (metres, e.g. 0.04; "
            "radians for a revolute jaw)"
        ) from None
    return width  # nan and out-of-range widths: the world names the valid range


def run(args: argparse.Namespace) -> int:
    action = parse_action(args.action)
    with connect_from(args) as client:
        gripper = client.arm(args.name).gripper
        if action == "open":
            state = gripper.open(force=args.force)
        elif action == "close":
            state = gripper.close(force=args.force)
        else:
            assert isinstance(action, float)
            state = gripper.move_to(action, force=args.force)
        if args.wait:
            state = gripper.wait(args.wait_timeout)
    print(f"{args.name}: {describe(state, gripper.width_unit)}")
    return 0


def describe(state: GripperState, unit: str = "m") -> str:
    """E.g. ``gripper closed, width 0.0000 m, not holding (t=1.234s)`` (``rad`` for a
    revolute jaw)."""
    holding = "holding" if state.holding else "not holding"
    width = f"{state.width:.4f} {unit}"
    return f"gripper {state.mode.value}, width {width}, {holding} (t={state.stamp:.3f}s)"
