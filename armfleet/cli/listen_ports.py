"""Ports a command-line run is told to listen on, checked before its world starts.

Taken, a ``--api-port`` failed only once every arm was up (its bring-up lines printed,
then the error), and a ``--viewer-port`` was dropped with a warning while the run went
on without the viewer it was asked for. Both are now refused in one line first. The
probe is a bind of the same address, so a port some other program takes in between is
still reported by the server that fails to listen there.
"""

from __future__ import annotations

import argparse
import socket

from armfleet.checks.network_address import DEFAULT_BIND as LOOPBACK  # the viewer's too
from armfleet.cli.parser import UsageError


def check_free(host: str, port: int, option: str, instead: str) -> None:
    """Raise :class:`UsageError` if nothing could listen on ``host``:``port`` now.

    Args:
        host: the address the server binds.
        port: the port given (0: a free one, always fine).
        option: the option that gave it, for the message.
        instead: what to give instead, for the message.
    """
    if port == 0:
        return
    family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
    with socket.socket(family, kind, proto) as probe:
        # As the servers do: a port only left in TIME_WAIT is free.
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as exc:
            raise UsageError(
                f"{option} {port}: cannot listen on {host}:{port} ({exc.strerror}); {instead}"
            ) from None


def check_run_ports(args: argparse.Namespace, viewer: bool) -> None:
    """Check the ``--viewer-port`` (when a viewer is to start), ``--api-port`` (when the
    API is served) and ``--foxglove`` port of a run."""
    viewer_port: int | None = args.viewer_port if viewer else None
    api_port: int | None = None
    if hasattr(args, "api_port") and not args.no_api:
        api_port = args.api_port
    if viewer_port and viewer_port == api_port:
        raise UsageError(f"--viewer-port and --api-port are both {api_port}; give two ports")
    if viewer_port:
        check_free(LOOPBACK, viewer_port, "--viewer-port", "choose another, or leave it out")
    if api_port:
        check_free(args.api_bind, api_port, "--api-port", "choose another, or 0 for a free one")
    foxglove_port: int | None = getattr(args, "foxglove", None)
    if foxglove_port and foxglove_port in (viewer_port, api_port):
        raise UsageError(
            f"--foxglove {foxglove_port} is also another server's port; give two ports"
        )
    if foxglove_port:
        check_free(
            args.foxglove_bind, foxglove_port, "--foxglove", "choose another, or 0 for a free one"
        )
