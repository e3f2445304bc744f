"""``--foxglove [PORT]``, ``--foxglove-bind HOST`` and ``--foxglove-rate HZ`` of the commands
that run a world."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from armfleet.checks.network_address import DEFAULT_BIND
from armfleet.checks.number_ranges import DEFAULT_FOXGLOVE_RATE_HZ, FOXGLOVE_RATE_HZ
from armfleet.cli.number_arguments import number_in, port_or_free
from armfleet.cli.parser import UsageError

if TYPE_CHECKING:
    from armfleet.foxglove import FoxgloveServer
    from armfleet.world import World

#: The port ``--foxglove`` alone listens on: the one Foxglove proposes.
DEFAULT_FOXGLOVE_PORT = 8765


def add_foxglove_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("Foxglove (docs/foxglove.md)")
    group.add_argument(
        "--foxglove", type=port_or_free, nargs="?", const=DEFAULT_FOXGLOVE_PORT, default=None,
        metavar="PORT",
        help=f"serve the world to Foxglove on ws://HOST:PORT (default port "
        f"{DEFAULT_FOXGLOVE_PORT}; 0: a free one)",
    )  # fmt: skip
    group.add_argument(
        "--foxglove-bind", default=DEFAULT_BIND, metavar="HOST",
        help=f"address Foxglove's server listens on (default {DEFAULT_BIND}: this machine "
        "only); any other lets other machines command the arms",
    )  # fmt: skip
    group.add_argument(
        "--foxglove-rate", type=number_in(FOXGLOVE_RATE_HZ), default=None, metavar="HZ",
        help=f"instants per simulated second of the streamed topics (/tf, joint and "
        f"controller states; default {DEFAULT_FOXGLOVE_RATE_HZ:g}); the step rate or more "
        "sends every step",
    )  # fmt: skip


def check_foxglove_arguments(args: argparse.Namespace) -> None:
    """Raise for a ``--foxglove-bind`` that is no address, or a ``--foxglove-bind`` or
    ``--foxglove-rate`` without ``--foxglove``."""
    bind = getattr(args, "foxglove_bind", DEFAULT_BIND)
    if getattr(args, "foxglove", None) is None:
        if bind != DEFAULT_BIND:
            raise UsageError("--foxglove-bind goes with --foxglove [PORT]; add it, or drop both")
        if getattr(args, "foxglove_rate", None) is not None:
            raise UsageError("--foxglove-rate goes with --foxglove [PORT]; add it, or drop both")
        return
    from armfleet.foxglove.server import check_host

    check_host(bind, "--foxglove-bind")


def start_foxglove(world: World, args: argparse.Namespace) -> FoxgloveServer | None:
    """Serve ``world`` to Foxglove if ``--foxglove`` says so; print its address (unless
    ``--quiet``) and, on stderr, a warning if other machines can reach it."""
    port = getattr(args, "foxglove", None)
    if port is None:
        return None
    rate = getattr(args, "foxglove_rate", None)
    rate = DEFAULT_FOXGLOVE_RATE_HZ if rate is None else rate
    from armfleet.foxglove import serve_foxglove  # the foxglove extra, loaded when asked for

    # As world.serve_foxglove: from the thread that steps the world, which this is.
    server = serve_foxglove(world, port, host=args.foxglove_bind, rate_hz=rate)
    if not getattr(args, "quiet", False):
        print(f"foxglove: {server.url}", flush=True)
    if server.exposed:
        print(
            f"armfleet: warning: the Foxglove server listens on {server.url}: anyone who can "
            "reach this machine there can command its arms",
            file=sys.stderr,
            flush=True,
        )
    return server
