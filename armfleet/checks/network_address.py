"""API addresses: ``tcp://HOST:PORT``, what a user may type, and which hosts are loopback."""

from __future__ import annotations

import ipaddress
import re

from armfleet.errors import ArmfleetError

DEFAULT_BIND = "127.0.0.1"
_ADDRESS = re.compile(r"^(?:tcp://)?(?P<host>\[[0-9a-fA-F:.]+\]|[A-Za-z0-9_.-]+|\*):(?P<port>\d+)$")


class AddressError(ArmfleetError):
    """An address that is not ``tcp://HOST:PORT``."""


def normalize_address(text: str) -> str:
    """``tcp://HOST:PORT`` from ``tcp://HOST:PORT``, ``HOST:PORT`` or ``PORT``."""
    text = text.strip()
    if text.isdigit():
        text = f"{DEFAULT_BIND}:{text}"
    match = _ADDRESS.match(text)
    if match is None or match["host"] == "*":
        raise AddressError(
            f"address {text!r} is malformed; give tcp://HOST:PORT, HOST:PORT or PORT "
            f"(e.g. tcp://{DEFAULT_BIND}:5555)"
        )
    port = int(match["port"])
    if not 1 <= port <= 65535:
        raise AddressError(f"port {port} in {text!r} is invalid; give 1-65535")
    return f"tcp://{match['host']}:{port}"


def check_bind_host(host: str) -> str:
    """``host`` if it is an IP address (or ``localhost``) a server can bind to."""
    if host == "localhost":
        return DEFAULT_BIND
    try:
        ipaddress.ip_address(host.strip("[]"))
    except ValueError:
        raise AddressError(
            f"--api-bind {host!r} is not an IP address; give one such as {DEFAULT_BIND} "
            "(default), 0.0.0.0 (every interface) or an address of this machine"
        ) from None
    return host


def is_loopback(host: str) -> bool:
    """Whether ``host`` is only reachable from this machine (127.0.0.0/8, ::1)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def bind_endpoint(host: str, port: int) -> str:
    """The ZeroMQ endpoint to bind: IPv6 hosts in brackets, port 0 for a free one."""
    host = check_bind_host(host)
    if ":" in host and not host.startswith("["):
        host = f"[{host}]"
    return f"tcp://{host}:{port}" if port else f"tcp://{host}:*"
