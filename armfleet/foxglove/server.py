"""A Foxglove WebSocket server for one world: topics, the arms' meshes, and services.

>>> server = world.serve_foxglove(8765)             # doctest: +SKIP
>>> server.url                                      # doctest: +SKIP
'ws://127.0.0.1:8765'

Open Foxglove, "Open connection", "Foxglove WebSocket", and give the URL. The
server is the ``foxglove-sdk`` package's (its Rust core runs the sockets in threads
of its own); armfleet gives it channels (:mod:`armfleet.foxglove.channels`), an
allowlisted asset handler (:mod:`armfleet.foxglove.assets`) and four services
(:mod:`armfleet.foxglove.services`). The world is only ever touched by the thread
that steps it: the server's threads hand work over with ``world.submit``.

A slow or stuck client never slows the world: the server keeps at most
:data:`BACKLOG_MESSAGES` messages per client and drops the oldest beyond that,
and the stepping thread only encodes a message and hands it over.
"""

from __future__ import annotations

import ipaddress
import logging
import threading
from typing import TYPE_CHECKING

import foxglove
from foxglove.websocket import Capability, ChannelView, Client, ServerListener, WebSocketServer

from armfleet.checks.network_address import DEFAULT_BIND, check_bind_host, is_loopback
from armfleet.checks.number_ranges import DEFAULT_FOXGLOVE_RATE_HZ, FOXGLOVE_RATE_HZ, PORT_OR_FREE
from armfleet.errors import ArmfleetError
from armfleet.foxglove.assets import AssetLibrary
from armfleet.foxglove.channels import JSON, TopicChannels
from armfleet.foxglove.errors import FoxgloveError
from armfleet.foxglove.services import ArmServices
from armfleet.world.world_listener import WorldListener

if TYPE_CHECKING:
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: The port Foxglove proposes for a WebSocket connection.
DEFAULT_PORT = 8765
#: Messages queued per client before the oldest are dropped.
BACKLOG_MESSAGES = 1024
#: Longest wait for the server to stop [s].
STOP_WAIT_S = 2.0
#: Name the server gives itself to its clients.
SERVER_NAME = "armfleet"
#: Instants of the streamed topics (``/tf``, joint and controller states) sent per
#: simulated second unless told.
DEFAULT_RATE_HZ = DEFAULT_FOXGLOVE_RATE_HZ


def check_host(host: object, option: str = "host") -> str:
    """``host`` if it is an IP address (or ``localhost``) to bind to, else FoxgloveError."""
    if isinstance(host, str):
        try:
            return check_bind_host(host)
        except ArmfleetError:
            pass
    raise FoxgloveError(
        f"{option} {host!r} is not an IP address; give one such as {DEFAULT_BIND} "
        "(default: this machine only), 0.0.0.0 (every interface) or an address of this machine"
    )


class _Listener(ServerListener):
    """The SDK's server listener: subscriptions reach the channels (server's thread)."""

    def __init__(self, channels: TopicChannels) -> None:
        self._channels = channels

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        self._channels.on_subscribe(channel.id)

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        self._channels.on_unsubscribe(channel.id)


class _WorldLink(WorldListener):
    """Closes the server with its world (first, while the bus still has its subscriptions)."""

    def __init__(self, server: FoxgloveServer) -> None:
        self._server = server

    def on_close(self) -> None:
        self._server.close()


class FoxgloveServer:
    """Serve ``world`` to Foxglove until :meth:`close` (or the world closes).

    Start it from the thread that steps the world, or while nobody steps it; the
    world must keep stepping (or calling ``world.process_requests()``) for
    subscriptions and service calls to be served.

    Args:
        world: the world served.
        port: TCP port, 0 for a free one (see :attr:`port`).
        host: address to listen on; 127.0.0.1 by default. Anything else lets other
            machines read the world and command its arms: pass it only on purpose.
        rate_hz: instants of the streamed topics (``/tf``, joint, controller and gripper
            states) sent per simulated second; None: every step. The other topics go
            out as published.

    Raises:
        FoxgloveError: bad host, port or rate, the port is taken, or the world is closed.
    """

    def __init__(
        self,
        world: World,
        port: int = 0,
        *,
        host: str = DEFAULT_BIND,
        rate_hz: float | None = DEFAULT_RATE_HZ,
    ) -> None:
        host = check_host(host)
        if not PORT_OR_FREE.contains(port):
            raise FoxgloveError(f"Foxglove port {port!r} is invalid; give {PORT_OR_FREE.valid}")
        if rate_hz is not None and not FOXGLOVE_RATE_HZ.contains(rate_hz):
            raise FoxgloveError(
                f"Foxglove rate {rate_hz!r} is invalid; give {FOXGLOVE_RATE_HZ.valid}, or None "
                "for every step"
            )
        #: Instants of the streamed topics sent per simulated second (None: every step).
        self.rate_hz = None if rate_hz is None else float(rate_hz)
        if world.closed:
            raise FoxgloveError("cannot serve a closed world to Foxglove")
        self._world = world
        self._host = host
        self._context = foxglove.Context()
        self._assets = AssetLibrary()
        self._server: WebSocketServer | None = None
        period = None if self.rate_hz is None else 1.0 / self.rate_hz
        self._channels = TopicChannels(
            world, self._context, self._assets, self._broadcast_time, period
        )
        self._lock = threading.Lock()
        try:
            self._server = foxglove.start_server(
                name=SERVER_NAME,
                host=host,
                port=int(port),
                capabilities=[Capability.Services, Capability.Time],
                server_listener=_Listener(self._channels),
                supported_encodings=[JSON],
                asset_handler=self._assets.fetch,
                context=self._context,
                message_backlog_size=BACKLOG_MESSAGES,
            )
        except Exception as exc:  # the SDK raises RuntimeError with the OS's reason
            raise FoxgloveError(
                f"cannot serve Foxglove on {host}:{port}: {exc}; choose another port, or 0 "
                "for a free one"
            ) from None
        self._closed = False
        self._link = _WorldLink(self)
        try:
            self._services = ArmServices(world, self.url)
            self._server.add_services(self._services.sdk_services())
            self._channels.start()
            world.attach(self._link)
        except BaseException:
            self.close()
            raise

    # -- properties -------------------------------------------------------------------
    @property
    def port(self) -> int:
        """The TCP port the server listens on."""
        assert self._server is not None
        return self._server.port

    @property
    def host(self) -> str:
        return self._host

    @property
    def url(self) -> str:
        """``ws://HOST:PORT``, what to give Foxglove's "Open connection"."""
        host = self._host
        if _is_ipv6(host):
            host = f"[{host.strip('[]')}]"
        return f"ws://{host}:{self.port}"

    @property
    def exposed(self) -> bool:
        """Whether other machines may reach the server."""
        return not is_loopback(self._host)

    @property
    def topics(self) -> list[str]:
        """The topics advertised now."""
        return self._channels.topics

    @property
    def listened(self) -> list[str]:
        """The bus topics the server listens to now (a client subscribed to them)."""
        return self._channels.listened

    @property
    def asset_uris(self) -> list[str]:
        """The ``package://`` URIs a client may fetch now (the allowlist)."""
        return self._assets.uris

    @property
    def messages_sent(self) -> int:
        """Messages handed to the server so far."""
        return self._channels.sent

    @property
    def closed(self) -> bool:
        return self._closed

    # -- lifetime ---------------------------------------------------------------------
    def close(self) -> None:
        """Stop serving: clients are disconnected, the bus subscriptions cancelled.
        Idempotent. Call it from the thread that steps the world, or once it stopped."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._world.detach(self._link)
        try:
            self._channels.close()
        finally:
            if self._server is not None:
                self._stop(self._server)

    @staticmethod
    def _stop(server: WebSocketServer) -> None:
        """Stop ``server``, waiting at most :data:`STOP_WAIT_S`: the SDK waits for every
        client to take its close frame, and one that does not read held a stop ~45 s
        (until its connection timed out). It goes on stopping in the background."""
        stopping = threading.Thread(target=server.stop, name="armfleet-foxglove-stop", daemon=True)
        stopping.start()
        stopping.join(STOP_WAIT_S)
        if stopping.is_alive():
            logger.warning(
                "foxglove: a client that does not read holds the server's shutdown; it ends "
                "when that connection times out"
            )

    def __enter__(self) -> FoxgloveServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else self.url
        return f"FoxgloveServer({state}, {len(self.topics)} topics)"

    def _broadcast_time(self, time_ns: int) -> None:
        server = self._server
        if server is not None and not self._closed:
            server.broadcast_time(time_ns)


def _is_ipv6(host: str) -> bool:
    try:
        return ipaddress.ip_address(host.strip("[]")).version == 6
    except ValueError:
        return False


def serve_foxglove(
    world: World,
    port: int = 0,
    *,
    host: str = DEFAULT_BIND,
    rate_hz: float | None = DEFAULT_RATE_HZ,
) -> FoxgloveServer:
    """Serve ``world`` to Foxglove; see :class:`FoxgloveServer`. Close it when done."""
    return FoxgloveServer(world, port, host=host, rate_hz=rate_hz)
