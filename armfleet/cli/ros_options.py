"""``--ros``, ``--ros-domain N``, ``--ros-rate HZ`` and ``--ros-network`` of the commands
that run a world (docs/ros2.md)."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from armfleet.checks.number_ranges import ROS_DOMAIN_ID, ROS_RATE_HZ
from armfleet.cli.number_arguments import integer_in, number_in
from armfleet.cli.parser import UsageError

if TYPE_CHECKING:
    from armfleet.ros import RosServer
    from armfleet.world import World

#: The options that need ``--ros``: (flag, attribute, default).
ROS_DETAILS = (
    ("--ros-domain", "ros_domain", None),
    ("--ros-rate", "ros_rate", None),
    ("--ros-network", "ros_network", False),
)


def add_ros_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("ROS 2 (docs/ros2.md)")
    group.add_argument(
        "--ros", action="store_true",
        help="serve the world to ROS 2 nodes: /clock, /tf, each arm's joint states and "
        "ros2_control controllers (needs armfleet[ros])",
    )  # fmt: skip
    group.add_argument(
        "--ros-domain", type=integer_in(ROS_DOMAIN_ID), default=None, metavar="N",
        help="ROS domain id (default: ROS_DOMAIN_ID, or 0)",
    )  # fmt: skip
    group.add_argument(
        "--ros-rate", type=number_in(ROS_RATE_HZ), default=None, metavar="HZ",
        help="instants of the streamed topics per simulated second (default: 100)",
    )  # fmt: skip
    group.add_argument(
        "--ros-network", action="store_true",
        help="let ROS 2 discovery and traffic leave this machine (default: loopback only)",
    )  # fmt: skip


def check_ros_arguments(args: argparse.Namespace) -> None:
    """Raise for a ``--ros-*`` option without ``--ros``, or ``--ros`` without ROS 2."""
    if not getattr(args, "ros", False):
        for flag, attribute, default in ROS_DETAILS:
            if getattr(args, attribute, default) != default:
                raise UsageError(f"{flag} goes with --ros; add it, or drop {flag}")
        return
    from armfleet.ros.availability import require_ros

    require_ros()  # before any arm comes up: one line with the install command


def start_ros(world: World, args: argparse.Namespace) -> RosServer | None:
    """Serve ``world`` to ROS 2 if ``--ros`` says so; print its node and domain."""
    if not getattr(args, "ros", False):
        return None
    from armfleet.ros import DEFAULT_RATE_HZ, serve_ros  # the ros extra, loaded when asked

    rate = args.ros_rate if args.ros_rate is not None else DEFAULT_RATE_HZ
    # As world.serve_ros: from the thread that steps the world, which this is.
    server = serve_ros(world, args.ros_domain, localhost_only=not args.ros_network, rate_hz=rate)
    if not getattr(args, "quiet", False):
        where = "other machines too" if args.ros_network else "this machine only"
        print(f"ros: node {server.node_name} on domain {server.domain_id} ({where})", flush=True)
    if args.ros_network:
        print(
            "armfleet: warning: --ros-network: ROS 2 nodes on other machines can see and "
            "command these arms",
            file=sys.stderr,
            flush=True,
        )
    return server
