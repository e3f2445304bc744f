"""``armfleet move NAME --joints q1 q2 ... | --pose X Y Z [ROLL PITCH YAW] [--wait]
[--avoid-collisions [--clearance M] [--planning-timeout S]]``: send an arm to joint
positions, or one of its links to a Cartesian pose, straight or planned around obstacles."""

from __future__ import annotations

import argparse

import numpy as np

from armfleet.checks.number_ranges import ANGLE_DEG, WORLD_COORDINATE_M
from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.number_arguments import wait_timeout
from armfleet.cli.number_format import fixed
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.planning_arguments import add_planning_arguments, planning_keywords
from armfleet.messages import FloatArray
from armfleet.objects.object_spec import pose_matrix
from armfleet.remote import Client
from armfleet.remote.remote_arm import WAIT_TIMEOUT_S, RemoteArm

POSE_SYNTAX = "X Y Z [ROLL PITCH YAW]"
#: Options of --pose only, and their defaults.
_POSE_OPTIONS = {"frame": "world", "link": "tool0", "linear": False}


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(
        subparsers, "move", "send an arm of the running world to joint positions or a pose"
    )
    parser.add_argument("name", metavar="NAME", help="arm name (see 'armfleet arms')")
    goal = parser.add_mutually_exclusive_group(required=True)
    goal.add_argument(
        "--joints", nargs="+", type=float, metavar="Q",
        help="target position per joint, base to tool [rad or m]",
    )  # fmt: skip
    goal.add_argument(
        "--pose", nargs="+", type=float, metavar="V",
        help=f"{POSE_SYNTAX}: where --link goes, in --frame [m, deg; R = Rz(yaw) Ry(pitch) "
        "Rx(roll)]; without the angles the link keeps its orientation",
    )  # fmt: skip
    parser.add_argument(
        "--frame", default=_POSE_OPTIONS["frame"], metavar="FRAME",
        help="frame of --pose: world (default), an arm's link (toby_tool0) or an object",
    )  # fmt: skip
    parser.add_argument(
        "--link", default=_POSE_OPTIONS["link"], metavar="LINK",
        help="the arm's link that --pose places (default tool0)",
    )  # fmt: skip
    # A straight tool line and a path around obstacles are two different motions.
    path = parser.add_mutually_exclusive_group()
    path.add_argument(
        "--linear", action="store_true",
        help="with --pose: a straight line from where the link is (the arm must be at rest)",
    )  # fmt: skip
    add_planning_arguments(parser, path)
    parser.add_argument("--wait", action="store_true", help="return once the arm holds the target")
    parser.add_argument(
        "--wait-timeout", type=wait_timeout, default=WAIT_TIMEOUT_S, metavar="S",
        help=f"longest wait for the motion with --wait [s] (default {WAIT_TIMEOUT_S:g})",
    )  # fmt: skip
    parser.set_defaults(run=run)
    parser.help_ranges["pose"] = f"X Y Z {WORLD_COORDINATE_M.valid}, angles {ANGLE_DEG.valid}"


def run(args: argparse.Namespace) -> int:
    if args.joints is not None:
        for option in _POSE_OPTIONS:
            if getattr(args, option) != _POSE_OPTIONS[option]:
                raise UsageError(f"--{option} goes with --pose, not --joints")
        return move_joints(args)
    return move_pose(args)


def move_joints(args: argparse.Namespace) -> int:
    planning = planning_keywords(args)
    with connect_from(args) as client:
        arm = client.arm(args.name)
        duration = arm.move_to(args.joints, **planning)
        target = " ".join(fixed(v, 3, "+") for v in args.joints)
        if not args.wait:
            how = " around obstacles" if planning else ""
            print(f"{arm.name}: moving to [{target}]{how}, {duration:.2f} s")
            return 0
        state = arm.wait(args.wait_timeout)
        print(f"{arm.name}: holding [{target}] at t={state.stamp:.3f}s")
    return 0


def move_pose(args: argparse.Namespace) -> int:
    values: list[float] = args.pose
    if len(values) not in (3, 6):
        raise UsageError(f"--pose takes {POSE_SYNTAX} (3 or 6 numbers: m, deg); got {len(values)}")
    for axis, angle in zip(("roll", "pitch", "yaw"), values[3:], strict=False):
        ANGLE_DEG.check(angle, f"--pose {axis}")  # the world checks the position
    goal = pose_matrix(values[:3], values[3:]) if len(values) == 6 else np.array(values)
    planning = planning_keywords(args)
    with connect_from(args) as client:
        arm = client.arm(args.name)
        duration = arm.move_to_pose(
            goal, args.frame, link=args.link, linear=args.linear, **planning
        )
        where = f"({', '.join(fixed(v, 4) for v in values[:3])}) m in {args.frame}"
        if not args.wait:
            how = " around obstacles" if planning else ""
            print(f"{arm.name}: moving {args.link} to {where}{how}, {duration:.2f} s")
            return 0
        state = arm.wait(args.wait_timeout)
        reached = _link_position(client, arm, args.frame, args.link)
        miss_mm = float(np.linalg.norm(reached - np.array(values[:3]))) * 1e3
        at = ", ".join(fixed(v, 4) for v in reached)
        print(
            f"{arm.name}: holding {args.link} at ({at}) m in {args.frame}, {miss_mm:.2f} mm from "
            f"the goal, t={state.stamp:.3f}s"
        )
    return 0


def _link_position(client: Client, arm: RemoteArm, frame: str, link: str) -> FloatArray:
    prefix = f"{arm.name}_"
    name = link if link.startswith(prefix) else prefix + link
    return client.lookup(frame, name)[:3, 3]
