"""The live API of a running world: one ZeroMQ ROUTER socket served by one thread.

The server thread never touches the world. It reads requests, checks them, and
hands the work to the stepping thread with ``world.submit`` (run at the next
step boundary, in order); a finished future wakes it to send the reply. Topic
messages reach it through bounded per-subscription queues filled by bus
callbacks in the stepping thread, which it empties every 2 ms in batches. So a
slow, dead or malicious client costs the world a few microseconds per message
at most.

Limits are per client: a client with too many requests in flight is refused
more, one reply each, while the others are served; every request gets exactly
one reply (held while its client does not read); and the requests of a client
that disconnects are cancelled (see :mod:`armfleet.remote.peer_watch`). The
world's owner sets what clients may add (:mod:`armfleet.remote.client_quotas`).
A ``step`` request steps in slices, so other clients are served while it runs
(:mod:`armfleet.remote.sliced_steps`), and a stream answers only to the client
that opened it (:mod:`armfleet.remote.streams`).
"""

from __future__ import annotations

import logging
import os
import threading
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import zmq

from armfleet.checks.flags import flag
from armfleet.checks.network_address import (
    DEFAULT_BIND,
    bind_endpoint,
    check_bind_host,
    is_loopback,
)
from armfleet.checks.number_ranges import REQUEST_TIMEOUT_S, WAIT_TIMEOUT_S
from armfleet.errors import ArmfleetError
from armfleet.remote import runtime_file
from armfleet.remote.client_quotas import ClientQuotas, QuotaLedger
from armfleet.remote.outbox import Outbox
from armfleet.remote.peer_watch import PeerWatch
from armfleet.remote.pending_requests import PendingRequests
from armfleet.remote.sliced_steps import SlicedSteps
from armfleet.remote.streams import StreamHub
from armfleet.remote.wakeup import Wakeup
from armfleet.services.arguments import Arguments
from armfleet.services.codec import unpack_request
from armfleet.services.errors import ProtocolError
from armfleet.services.protocol import (
    HARD_FRAME_LIMIT_BYTES,
    PROTOCOL_VERSION,
    TICK_PERIOD_S,
    Service,
    armfleet_version,
)
from armfleet.services.run_state import RunState
from armfleet.services.world_services import FIELDS, WorldServices, require_known
from armfleet.world import World

logger = logging.getLogger("armfleet")

#: Wait of a request in the world's queue when the client names none [s].
DEFAULT_REQUEST_TIMEOUT_S = 30.0
#: Frames ZeroMQ queues for one peer before the server holds back (then drops oldest).
SEND_HWM = 64
#: Period at which queued topic messages are sent [s]: at most this much added latency.
STREAM_FLUSH_PERIOD_S = 0.002
#: Requests read in one go before replies and streams get a turn.
READ_BURST = 256
_REQUEST_KEYS = ("id", "op", "args", "timeout_s")
#: Fields of ``attach``: the key of the request connection that owns the stream.
_ATTACH_FIELDS = ("owner",)


class ServerError(ArmfleetError):
    """The API could not start (address in use, bad bind address)."""


class WorldServer:
    """Serve ``world`` on ``tcp://HOST:PORT`` until :meth:`close`.

    Args:
        world: the world; whoever steps it must keep stepping (or, when paused,
            calling ``world.process_requests()``) for requests to be served.
        run_state: the stepping loop's run control (pause/resume/step/RTF);
            without one those services are refused.
        host: address to listen on; 127.0.0.1 by default. Anything else lets
            other machines command the world: pass it only on purpose.
        port: TCP port; a free one if 0.
        register: name this world in the per-user runtime file, so that clients
            find it without an address (unless another running world holds it).
        quotas: what each client, and all clients together, may add (arms, objects,
            requests in flight); :class:`ClientQuotas`' defaults if None.

    Raises:
        ServerError: the address cannot be bound.
        ArmfleetError: ``quotas`` is not a :class:`ClientQuotas`.
    """

    def __init__(
        self,
        world: World,
        run_state: RunState | None = None,
        *,
        host: str = DEFAULT_BIND,
        port: int = 0,
        register: bool = True,
        quotas: ClientQuotas | None = None,
    ) -> None:
        host = check_bind_host(host)
        if quotas is None:
            quotas = ClientQuotas()
        elif not isinstance(quotas, ClientQuotas):
            raise ArmfleetError(
                f"quotas must be an armfleet.remote.ClientQuotas (or None for the defaults), "
                f"got {type(quotas).__name__}"
            )
        #: What clients may add, as the world's owner set it.
        self.quotas = quotas
        self._ledger = QuotaLedger(quotas)
        register = flag(register, "register")  # 'no' would name this world to every client
        self._world = world
        self._run_state = run_state
        self._context = zmq.Context()
        self._socket = self._context.socket(zmq.ROUTER)
        self._configure_socket(host)
        try:
            self._socket.bind(bind_endpoint(host, port))
        except zmq.ZMQError as exc:
            self._socket.close()
            self._context.term()
            raise ServerError(
                f"cannot listen on {host}:{port}: {exc.strerror}; choose another --api-port, "
                "or 0 for a free one"
            ) from None
        #: The address the socket is bound to, ``tcp://HOST:PORT``.
        self.address: str = self._socket.getsockopt_string(zmq.LAST_ENDPOINT)
        port_text = self.address.rsplit(":", 1)[1]
        wildcard = host in ("0.0.0.0", "::", "[::]")
        #: The address local clients use (what the runtime file holds).
        self.local_address = f"tcp://{DEFAULT_BIND}:{port_text}" if wildcard else self.address
        #: Whether other machines may reach the API.
        self.exposed = not is_loopback(host)
        self._wakeup = Wakeup()
        outbox = Outbox(self._socket)
        self._services = WorldServices(world, run_state, self.address)
        self._pending = PendingRequests(
            world, outbox, self._wakeup, run_state, quotas.requests_per_client
        )
        self._streams = StreamHub(world, outbox)
        self._outbox = outbox
        self._peers = PeerWatch(self._socket)
        self._stopping = threading.Event()
        self._closed = False
        #: The runtime file naming this world, or None (not asked, or another world holds it).
        self.runtime_path: Path | None = None
        if register:
            self.runtime_path = runtime_file.write_entry(self.local_address)
        self._thread = threading.Thread(target=self._serve, name="armfleet-api", daemon=True)
        self._thread.start()

    def _configure_socket(self, host: str) -> None:
        for option, value in (
            (zmq.LINGER, 0),
            (zmq.ROUTER_MANDATORY, 1),  # report full or vanished peers instead of dropping
            (zmq.MAXMSGSIZE, HARD_FRAME_LIMIT_BYTES),
            (zmq.SNDHWM, SEND_HWM),
            (zmq.HEARTBEAT_IVL, 1000),
            (zmq.HEARTBEAT_TIMEOUT, 5000),
            (zmq.HEARTBEAT_TTL, 5000),
        ):
            self._socket.setsockopt(option, value)
        if ":" in host:
            self._socket.setsockopt(zmq.IPV6, 1)

    @property
    def stream_count(self) -> int:
        """Clients receiving topics now."""
        return len(self._streams.streams)

    @property
    def subscription_count(self) -> int:
        return self._streams.subscription_count

    def close(self) -> None:
        """Stop serving: streams are told, pending requests answered, the runtime file removed."""
        if self._closed:
            return
        self._closed = True
        self._stopping.set()
        self._wakeup.signal()
        self._thread.join(timeout=5.0)
        if self._thread.is_alive():
            logger.warning("the API thread did not stop within 5 s")
        if self.runtime_path is not None:
            runtime_file.remove_entry(self.runtime_path)
        self._wakeup.close()

    def __enter__(self) -> WorldServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the server thread ------------------------------------------------------------
    def _serve(self) -> None:
        poller = zmq.Poller()
        poller.register(self._socket, zmq.POLLIN)
        poller.register(self._wakeup.fileno(), zmq.POLLIN)
        poller.register(self._peers.monitor, zmq.POLLIN)
        next_tick = time.monotonic() + TICK_PERIOD_S
        try:
            while not self._stopping.is_set():
                wake_at = min(next_tick, self._pending.next_deadline() or next_tick)
                timeout = wake_at - time.monotonic()
                if self._streams.subscription_count or self._outbox.holding:
                    # Streams are flushed on this beat, in batches: cheaper for the world
                    # than a wake-up per message.
                    timeout = min(timeout, STREAM_FLUSH_PERIOD_S)
                poller.poll(max(0, round(timeout * 1000)))
                self._wakeup.clear()
                self._forget(self._peers.departed())
                self._receive()
                self._pending.answer_completed()
                self._pending.expire()
                self._forget(self._outbox.flush())
                self._streams.flush()
                if time.monotonic() >= next_tick:
                    self._streams.tick()
                    next_tick = time.monotonic() + TICK_PERIOD_S
        except Exception:
            logger.exception("the API server failed; the world goes on without it")
        finally:
            reason = "the world is shutting down"
            self._streams.close(reason)
            self._pending.fail_all(reason)
            self._peers.close()
            self._socket.close(linger=200)
            self._context.term()

    def _receive(self) -> None:
        batch = []
        for _ in range(READ_BURST):
            try:
                batch.append(self._socket.recv_multipart(zmq.NOBLOCK, copy=False))
            except zmq.Again:
                break
        if not batch:
            return
        # The connection events up to these requests, before noting who sent them (see
        # PeerWatch: a descriptor closed and reused meanwhile is not taken for the new one).
        self._forget(self._peers.departed())
        for frames in batch:
            peer = frames[0].bytes
            if self._peers.has_departed(peer):
                continue  # read after its client left: nobody to answer, nothing to do
            self._peers.note(peer, frames[0])
            self._on_request(peer, [frame.bytes for frame in frames[1:]])

    def _forget(self, peers: list[bytes]) -> None:
        """Cancel the requests and streams of clients that disconnected."""
        for peer in peers:
            cancelled = self._pending.cancel_client(peer)
            self._outbox.forget(peer)
            self._streams.detach(peer, None)
            self._streams.forget_connection(peer)
            self._ledger.forget(peer)
            if cancelled:
                logger.info("a client went away; cancelled its %d request(s)", cancelled)

    def _on_request(self, peer: bytes, parts: list[bytes]) -> None:
        request_id: int | None = None
        try:
            if len(parts) != 1:
                raise ProtocolError(f"a request is one frame; got {len(parts)}")
            request = unpack_request(parts[0])
            if not isinstance(request, dict):
                raise ProtocolError(
                    "a request must be a map with 'id', 'op' and 'args'; got "
                    f"{type(request).__name__}"
                )
            raw_id = request.get("id")
            if isinstance(raw_id, int) and not isinstance(raw_id, bool):
                request_id = raw_id  # answer with it, even if the rest is wrong
            top = Arguments("request", request, _REQUEST_KEYS, label="the request")
            top.integer("id", low=0, high=2**63 - 1)
            service = require_known(top.text("op"))
            timeout = top.in_range("timeout_s", DEFAULT_REQUEST_TIMEOUT_S, REQUEST_TIMEOUT_S)
            fields = _ATTACH_FIELDS if service is Service.ATTACH else FIELDS[service]
            args = Arguments(service.value, request.get("args"), fields)
            self._dispatch(peer, request_id, service, args, timeout)
        except ArmfleetError as exc:
            logger.info("refused a request: %s", exc)
            self._outbox.reply_error(peer, request_id, exc)
        except Exception as exc:
            logger.exception("failed to handle a request")
            self._outbox.reply_error(peer, request_id, exc)

    def _dispatch(
        self, peer: bytes, request_id: int | None, service: Service, args: Arguments, timeout: float
    ) -> None:
        reply = self._outbox.reply
        if service is Service.HELLO:
            reply(peer, request_id, self._hello(peer, args))
        elif service is Service.ATTACH:
            stream = self._streams.attach(peer, args.text("owner", None))
            reply(peer, request_id, {"stream": stream.token})
        elif service is Service.DETACH:
            self._streams.detach(peer, args.text("stream", None))
            reply(peer, request_id, None)
        elif service is Service.UNSUBSCRIBE:
            self._streams.unsubscribe(peer, args)
            reply(peer, request_id, None)
        elif service is Service.SUBSCRIBE:
            topic, queue, register = self._streams.prepare_subscription(peer, args)
            subscribe = self._services.subscribe(topic, queue)
            self._pending.submit(peer, request_id, service, subscribe, timeout, register)
        elif service is Service.STEP:
            steps = SlicedSteps.from_request(self._world, self._run_state, args, timeout)
            self._pending.repeat(peer, request_id, service, steps, wake=True)
        elif service is Service.WAIT:
            name = args.text("name")
            duration = args.in_range("timeout_s", timeout, WAIT_TIMEOUT_S)
            if args.flag("gripper", False):
                check, what = self._services.gripper_wait_check(name), f"{name}'s gripper"
            else:
                check, what = self._services.wait_check(name), name
            self._pending.wait(peer, request_id, check, duration, f"{what} is still moving")
        else:
            work = self._services.prepare(service, args)
            assert work is not None  # every other service is plain
            world = self._world
            if service is Service.SPAWN:
                work = self._ledger.spawning(peer, args.text("name"), lambda: world.arms, work)
            elif service is Service.ADD_OBJECT:
                name = args.text("name")
                work = self._ledger.adding_object(peer, name, lambda: world.objects, work)
            finish = self._add_server_info if service is Service.INFO else None
            self._pending.submit(peer, request_id, service, work, timeout, finish)

    def _hello(self, peer: bytes, args: Arguments) -> dict[str, Any]:
        protocol = args.integer("protocol", low=0, high=2**31)
        if protocol != PROTOCOL_VERSION:
            raise ProtocolError(
                f"the client speaks protocol {protocol}, this world {PROTOCOL_VERSION}; use "
                f"the same armfleet version on both sides (the world runs {armfleet_version()})"
            )
        return {
            "protocol": PROTOCOL_VERSION,
            "version": armfleet_version(),
            "pid": os.getpid(),
            "address": self.address,
            # The stream socket of this client attaches with it: the stream is then theirs.
            "connection": self._streams.connection_key(peer),
        }

    def _add_server_info(self, info: dict[str, Any]) -> dict[str, Any]:
        return info | {
            "pid": os.getpid(),
            "streams": len(self._streams.streams),
            "subscriptions": self._streams.subscription_count,
            "requests": self._pending.in_flight(),
            "quotas": asdict(self.quotas),
        }


def serve(
    world: World,
    run_state: RunState | None = None,
    *,
    host: str = DEFAULT_BIND,
    port: int = 0,
    register: bool = True,
    quotas: ClientQuotas | None = None,
) -> WorldServer:
    """Serve ``world``'s live API; see :class:`WorldServer`. Close it when done."""
    return WorldServer(world, run_state, host=host, port=port, register=register, quotas=quotas)
