"""Ray for a sweep: a private local instance on the loopback interface, or a cluster the
user names by address.

A local instance (no address) is started with ``address="local"``, so it never joins a
cluster it happens to find (``RAY_ADDRESS``, a head node left running), with no
dashboard, and with every port it opens on 127.0.0.1: Ray binds its ports to the node's
address, which is the loopback one when ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0`` is in
the environment as Ray is imported (as on a laptop running macOS); by default it would
listen on all interfaces. Joining a cluster by address is the user's explicit choice.
"""

from __future__ import annotations

import ipaddress
import logging
import os
import shutil
import socket
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import ModuleType
from urllib.parse import urlsplit

from armfleet.sweeps.errors import SweepError

#: Ray reads it once, when imported: "0" makes a local node use the loopback address.
LOOPBACK_SWITCH = "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"
#: How long the reachability check of a cluster's address waits [s].
CONNECT_TIMEOUT_S = 5.0
#: Ray's default GCS port, for an address given without one.
DEFAULT_PORTS = {"ray": 10001, "": 6379}


@dataclass(frozen=True)
class RaySession:
    """The Ray a sweep runs on.

    Attributes:
        ray: the imported ``ray`` module.
        local: a private instance this sweep started (and shuts down).
        workers: tasks to keep running at once.
        address: what was joined, or ``"local"``.
    """

    ray: ModuleType
    local: bool
    workers: int
    address: str


def check_address(address: str) -> None:
    """Refuse an address that names no reachable cluster, before anything starts.

    ``auto`` needs a cluster started on this machine (``ray start --head``) or
    ``RAY_ADDRESS``; ``ray://HOST:PORT`` and ``HOST:PORT`` must accept a connection.

    Raises:
        SweepError: one line, naming the address and what to do.
    """
    if address == "auto":
        if os.environ.get("RAY_ADDRESS"):
            return check_address(os.environ["RAY_ADDRESS"])
        marker = os.path.join(_ray_temp_dir(), "ray_current_cluster")
        if not os.path.exists(marker):
            raise SweepError(
                "--address auto: no Ray cluster is running on this machine (start one with "
                "'ray start --head', give ray://HOST:PORT, or leave --address out for a "
                "private local instance)"
            )
        return None
    parts = urlsplit(address if "://" in address else f"//{address}")
    if parts.scheme not in ("", "ray"):
        raise SweepError(
            f"--address {address!r}: give auto, ray://HOST:PORT or HOST:PORT "
            f"(scheme {parts.scheme!r} is not Ray's)"
        )
    try:
        host, port = parts.hostname, parts.port or DEFAULT_PORTS[parts.scheme]
    except ValueError as exc:
        raise SweepError(f"--address {address!r}: {exc}") from None
    if not host:
        raise SweepError(f"--address {address!r}: no host; give ray://HOST:PORT")
    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S):
            pass
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise SweepError(
            f"cannot reach a Ray cluster at {address} ({host}:{port}: {reason}); start one "
            "with 'ray start --head', or leave --address out for a private local instance"
        ) from None
    return None


@contextmanager
def ray_session(address: str | None, workers: int | None) -> Iterator[RaySession]:
    """Start a private local Ray (``address`` None) with ``workers`` CPUs (default: all
    cores), or join the cluster at ``address`` (checked by :func:`check_address` first,
    before anything else starts); shut down or disconnect at the end.

    Raises:
        SweepError: a cluster that refuses the join, or ``ray`` already imported without
            the loopback switch when a local instance is asked for.
    """
    ray = _import_ray(local=address is None or _is_loopback(address))
    if ray.is_initialized():
        raise SweepError(
            "Ray is already initialized in this process; call ray.shutdown() first, or "
            "let the sweep start and stop its own"
        )
    private = None
    if address is None:
        count = workers or os.cpu_count() or 1
        # Its own folder: no other program finds it there (Ray's default folder names the
        # last cluster started, for any ray.init() to join), and nothing is left behind.
        private = tempfile.mkdtemp(prefix="armfleet-ray-")
        ray.init(
            address="local",
            num_cpus=count,
            include_dashboard=False,
            log_to_driver=False,
            logging_level=logging.ERROR,
            _temp_dir=private,
        )
        session = RaySession(ray, True, count, "local")
    else:
        try:
            ray.init(address=address, log_to_driver=False, logging_level=logging.ERROR)
        except Exception as exc:  # Ray raises several kinds for a refused connection
            hint = ""
            if address != "auto" and "RAY_AUTH_MODE" not in os.environ:
                hint = " (a cluster with token authentication, Ray's default, needs "
                hint += "RAY_AUTH_MODE=token for an address given explicitly)"
            raise SweepError(f"cannot join the Ray cluster at {address}: {exc}{hint}") from None
        cpus = int(ray.cluster_resources().get("CPU", 1))
        session = RaySession(ray, False, workers or max(1, cpus), address)
    try:
        yield session
    finally:
        ray.shutdown()
        if private is not None:
            shutil.rmtree(private, ignore_errors=True)


def _is_loopback(address: str) -> bool:
    """Whether ``address`` (``auto``: the cluster started here) is on the loopback interface:
    a driver joining such a cluster must take the loopback address as its node's too (Ray
    would otherwise put the machine's address in place of 127.0.0.1 and miss the cluster)."""
    if address == "auto":
        try:
            with open(os.path.join(_ray_temp_dir(), "ray_current_cluster")) as marker:
                address = marker.read().strip()
        except OSError:
            return False
    if address.startswith("ray://"):
        return False  # a Ray Client needs no node address of its own
    host = urlsplit(f"//{address}").hostname or ""
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return host == "localhost"


def _import_ray(*, local: bool) -> ModuleType:
    """``ray``, imported with a loopback node address when ``local``."""
    if "ray" not in sys.modules and local:
        os.environ[LOOPBACK_SWITCH] = "0"  # before Ray reads it, as it is imported
    import ray
    from ray._private import ray_constants

    if local and ray_constants.ENABLE_RAY_CLUSTER:
        raise SweepError(
            "ray was imported before armfleet could keep a local instance on 127.0.0.1; "
            f"set {LOOPBACK_SWITCH}=0 before importing ray, or run the sweep first"
        )
    return ray


def _ray_temp_dir() -> str:
    return os.environ.get("RAY_TMPDIR", "/tmp/ray")
