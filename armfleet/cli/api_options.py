"""The live API on the command line: serving it from a world, reaching it from a client."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from armfleet.checks.network_address import DEFAULT_BIND, check_bind_host
from armfleet.cli.number_arguments import integer_in, port_or_free, request_timeout
from armfleet.cli.parser import OneLineParser
from armfleet.remote.client import DEFAULT_TIMEOUT_S, Client, connect
from armfleet.remote.client_quotas import (
    QUOTA_COUNT,
    QUOTA_REQUESTS,
    RAISED_BY,
    ClientQuotas,
)

if TYPE_CHECKING:  # the server side loads only for the commands that start a world
    from armfleet.remote.server import WorldServer
    from armfleet.services.run_state import RunState
    from armfleet.world import World

#: Longest time one thread of the world process holds the GIL when others wait [s].
GIL_SWITCH_S = 0.001


# -- commands that start a world ---------------------------------------------------------
def add_api_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("live API (armfleet arms, move, topic ... talk to it)")
    group.add_argument(
        "--api-bind", default=DEFAULT_BIND, metavar="HOST",
        help=f"address the API listens on (default {DEFAULT_BIND}: this machine only); any "
        "other lets other machines command the world",
    )  # fmt: skip
    group.add_argument(
        "--api-port", type=port_or_free, default=0, metavar="PORT",
        help="TCP port of the API (default: a free one)",
    )  # fmt: skip
    group.add_argument("--no-api", action="store_true", help="do not serve the live API")
    add_quota_arguments(parser)


#: What each quota option bounds, for its help.
_QUOTA_HELP = {
    "arms_per_client": "arms one client may have in the world",
    "objects_per_client": "objects one client may have in the world",
    "requests_per_client": "requests one client may have in flight",
    "world_arms": "arms in the world (whoever spawned them) past which clients spawn none",
    "world_objects": "objects in the world past which clients add none",
}


def add_quota_arguments(parser: argparse.ArgumentParser) -> None:
    """The world's capacity policy for its clients (:class:`ClientQuotas`)."""
    group = parser.add_argument_group(
        "capacity (what clients of the live API may add; refused past it, in one line)"
    )
    defaults = ClientQuotas()
    for quota, option in RAISED_BY.items():
        valid = QUOTA_REQUESTS if quota == "requests_per_client" else QUOTA_COUNT
        group.add_argument(
            option, dest=f"quota_{quota}", type=integer_in(valid),
            default=getattr(defaults, quota), metavar="N",
            help=f"{_QUOTA_HELP[quota]} (default {getattr(defaults, quota)})",
        )  # fmt: skip


def quotas_from(args: argparse.Namespace) -> ClientQuotas:
    """The quotas the options set (the defaults for those not given)."""
    defaults = ClientQuotas()
    return ClientQuotas(
        **{quota: getattr(args, f"quota_{quota}", getattr(defaults, quota)) for quota in RAISED_BY}
    )


def check_api_arguments(args: argparse.Namespace) -> None:
    check_bind_host(args.api_bind)


def start_api(world: World, run_state: RunState, args: argparse.Namespace) -> WorldServer | None:
    """Serve ``world`` as the options say; print its address (unless ``--quiet``: clients
    find it anyway) and, on stderr, a warning if other machines can reach it."""
    from armfleet.remote.server import WorldServer

    if getattr(args, "no_api", False):
        return None
    # Let the stepping and the server threads take turns every 1 ms rather than 5 ms:
    # a reply then waits for about one step, not a long slice of stepping.
    sys.setswitchinterval(min(sys.getswitchinterval(), GIL_SWITCH_S))
    server = WorldServer(
        world,
        run_state,
        host=getattr(args, "api_bind", DEFAULT_BIND),
        port=getattr(args, "api_port", 0),
        quotas=quotas_from(args),
    )
    if not getattr(args, "quiet", False):
        print(f"api: {server.address}", flush=True)
    if server.exposed:
        print(
            f"armfleet: warning: the live API listens on {server.address}: anyone who can reach "
            "this machine there can command its arms",
            file=sys.stderr,
            flush=True,
        )
    if server.runtime_path is None:
        print(
            "armfleet: note: another running world is the default for clients; reach this one "
            f"with --connect {server.local_address}",
            file=sys.stderr,
            flush=True,
        )
    return server


# -- client commands ---------------------------------------------------------------------
def add_connect_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--connect", metavar="ADDR", default=None,
        help="address of the world's API, tcp://HOST:PORT (default: the running world, "
        "found through the per-user runtime file)",
    )  # fmt: skip
    parser.add_argument(
        "--timeout", type=request_timeout, default=DEFAULT_TIMEOUT_S, metavar="S",
        help=f"wait for the world's answers [s] (default {DEFAULT_TIMEOUT_S:g})",
    )  # fmt: skip


def connect_from(args: argparse.Namespace) -> Client:
    """Connect as ``--connect``/``--timeout`` say (parsing checked ``--timeout``)."""
    return connect(args.connect, timeout=args.timeout)


def add_remote_command(
    subparsers: argparse._SubParsersAction[OneLineParser], name: str, help_text: str
) -> OneLineParser:
    """A client command: ``--connect`` and ``--timeout`` included."""
    parser = subparsers.add_parser(
        name, help=help_text, description=help_text[0].upper() + help_text[1:] + "."
    )
    add_connect_arguments(parser)
    return parser
