"""Server side of the client streams: which subscriptions each stream holds, and batching.

A stream belongs to the client that opened it. A client talks to the world on two
connections: requests on one, topic messages pushed on the other (its stream socket).
``hello`` on the request connection returns a key naming that connection, and the
stream socket attaches with it (``attach {"owner": key}``); from then on, only those two
connections may ``subscribe``, ``unsubscribe`` or ``detach`` on that stream. A stream
attached without a key answers only to its own socket. Any other connection naming its
token is refused with :class:`StreamNotYours`, the stream untouched. Before, a client
holding another's token could detach its stream or cancel its subscriptions, and that
client went on believing them active while receiving nothing.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from armfleet.errors import ArmfleetError
from armfleet.remote.outbox import Delivery, Outbox
from armfleet.runtime.bus import Subscription
from armfleet.services.arguments import Arguments
from armfleet.services.codec import pack, to_wire
from armfleet.services.errors import ConnectionLost, ProtocolError
from armfleet.services.protocol import (
    DEFAULT_QUEUE_SIZE,
    MAX_BATCH,
    MAX_QUEUE_SIZE,
    MAX_STREAMS,
    MAX_SUBSCRIPTIONS_PER_STREAM,
    FrameKind,
)
from armfleet.services.subscription_queue import SubscriptionQueue
from armfleet.world import World

logger = logging.getLogger("armfleet")


class StreamNotYours(ArmfleetError):
    """A request named the stream of another client; nothing was changed.

    Attributes:
        service: the refused request (``subscribe``, ``unsubscribe``, ``detach``).
    """

    def __init__(self, service: str) -> None:
        self.service = service
        super().__init__(
            f"{service}: that stream belongs to another client, which alone may subscribe, "
            "unsubscribe or detach on it; attach a stream of your own (nothing was changed)"
        )


@dataclass(eq=False)
class ActiveSubscription:
    """One topic a stream receives.

    Attributes:
        key: the number the client gave it (unique in its stream).
        topic: the bus topic.
        type_name: the topic's message type.
        queue: messages waiting to be sent, filled by the stepping thread.
        handle: the bus subscription (cancelled in the stepping thread).
    """

    key: int
    topic: str
    type_name: str
    queue: SubscriptionQueue
    handle: Subscription


@dataclass(eq=False)
class Stream:
    """A client's stream socket: the ZeroMQ peer the server pushes its topics to.

    Attributes:
        peer: the ROUTER routing id of the client's stream socket.
        token: the name the client uses for it in requests.
        owner: the routing id of the client's request connection, named by the key the
            stream attached with (None: none); only it and the stream socket act on it.
        subscriptions: by key.
        held: a frame ZeroMQ refused (the client is slow), sent before any other.
        closed: dropped by the server; late results for it are undone.
    """

    peer: bytes
    token: str
    owner: bytes | None = None
    subscriptions: dict[int, ActiveSubscription] = field(default_factory=dict)
    held: bytes | None = None
    closed: bool = False
    _cursor: int = 0

    def take_batch(self, limit: int) -> list[list[Any]]:
        """Up to ``limit`` queued messages, oldest first, taken in turn from each
        subscription: ``[key, dropped so far, type, message]`` each."""
        active = [s for s in self.subscriptions.values() if len(s.queue)]
        items: list[list[Any]] = []
        if not active:
            return items
        start = self._cursor % len(active)
        active = active[start:] + active[:start]
        while active and len(items) < limit:
            for subscription in tuple(active):
                message = subscription.queue.pop()
                if message is None:
                    active.remove(subscription)
                    continue
                items.append(
                    [
                        subscription.key,
                        subscription.queue.dropped,
                        subscription.type_name,
                        to_wire(message),
                    ]
                )
                if len(items) >= limit:
                    break
        self._cursor += 1
        return items


class StreamHub:
    """The streams of one server and the subscriptions they hold (server thread only).

    Args:
        world: the world whose bus the subscriptions are on.
        outbox: where frames go.
    """

    def __init__(self, world: World, outbox: Outbox) -> None:
        self._world = world
        self._outbox = outbox
        self._by_peer: dict[bytes, Stream] = {}
        self._by_token: dict[str, Stream] = {}
        #: Keys naming request connections (handed out by ``hello``), both ways.
        self._key_of: dict[bytes, str] = {}
        self._peer_of: dict[str, bytes] = {}

    @property
    def streams(self) -> tuple[Stream, ...]:
        return tuple(self._by_peer.values())

    @property
    def subscription_count(self) -> int:
        return sum(len(s.subscriptions) for s in self.streams)

    def connection_key(self, peer: bytes) -> str:
        """The key naming the request connection ``peer`` (made on first use), which its
        client's stream socket attaches with to make the stream theirs."""
        key = self._key_of.get(peer)
        if key is None:
            key = self._key_of[peer] = os.urandom(16).hex()
            self._peer_of[key] = peer
        return key

    def forget_connection(self, peer: bytes) -> None:
        """``peer`` has disconnected: its key names nobody any more."""
        key = self._key_of.pop(peer, None)
        if key is not None:
            del self._peer_of[key]

    def attach(self, peer: bytes, owner_key: str | None = None) -> Stream:
        """The stream of ``peer`` (created on first use), owned by the request connection
        ``owner_key`` names (see :meth:`connection_key`), if any.

        Raises:
            ProtocolError: ``owner_key`` names no connection of this world.
        """
        owner = None
        if owner_key is not None:
            owner = self._peer_of.get(owner_key)
            if owner is None:
                raise ProtocolError(
                    "attach: 'owner' names no connection of this world; give the key that "
                    "'hello' returned ('connection') on this client's request connection"
                )
        stream = self._by_peer.get(peer)
        if stream is not None:
            if owner is not None and stream.owner not in (None, owner):
                raise StreamNotYours("attach")
            stream.owner = stream.owner or owner
            return stream
        if len(self._by_peer) >= MAX_STREAMS:
            raise ArmfleetError(f"this world serves {MAX_STREAMS} streams already; try later")
        stream = Stream(peer, os.urandom(8).hex(), owner)
        self._by_peer[peer] = stream
        self._by_token[stream.token] = stream
        return stream

    def stream(self, token: str, service: str, peer: bytes) -> Stream:
        """The stream named ``token``, for a request of ``peer``.

        Raises:
            ProtocolError: no such stream.
            StreamNotYours: ``peer`` is neither the stream's socket nor its owner.
        """
        found = self._by_token.get(token)
        if found is None:
            raise ProtocolError(f"{service}: no stream {token!r}; attach a stream first")
        if peer not in (found.peer, found.owner):
            raise StreamNotYours(service)
        return found

    def detach(self, peer: bytes, token: str | None) -> None:
        """Drop the stream of ``peer`` (its stream socket), else the one named ``token``.

        Raises:
            StreamNotYours: ``token`` names another client's stream.
        """
        stream = self._by_peer.get(peer)
        if stream is None and token:
            stream = self._by_token.get(token)
            if stream is not None:
                stream = self.stream(token, "detach", peer)
        if stream is not None:
            self.drop(stream, None)

    def prepare_subscription(
        self, peer: bytes, args: Arguments
    ) -> tuple[str, SubscriptionQueue, Callable[[Any], dict[str, Any]]]:
        """Check a subscribe request; return its topic, its queue, and what to do once the
        stepping thread has subscribed the queue (register it, or undo if the stream left)."""
        stream = self.stream(args.text("stream"), "subscribe", peer)
        topic = args.text("topic")
        key = args.integer("sub", low=0, high=2**63)
        rate = args.number("rate_hz", None, low=1e-3, high=1e6)
        size = args.integer("queue_size", DEFAULT_QUEUE_SIZE, low=1, high=MAX_QUEUE_SIZE)
        if key in stream.subscriptions:
            raise ProtocolError(f"subscribe: subscription {key} exists already on this stream")
        if len(stream.subscriptions) >= MAX_SUBSCRIPTIONS_PER_STREAM:
            raise ArmfleetError(
                f"subscribe: a stream holds at most {MAX_SUBSCRIPTIONS_PER_STREAM} subscriptions"
            )
        queue = SubscriptionQueue(size, rate)

        def register(result: Any) -> dict[str, Any]:
            handle, type_name = result
            subscription = ActiveSubscription(key, topic, type_name, queue, handle)
            if stream.closed or key in stream.subscriptions:
                self._cancel(subscription)
                raise ConnectionLost("subscribe: the stream went away meanwhile")
            stream.subscriptions[key] = subscription
            return {"sub": key, "type": type_name}

        return topic, queue, register

    def unsubscribe(self, peer: bytes, args: Arguments) -> None:
        stream = self.stream(args.text("stream"), "unsubscribe", peer)
        subscription = stream.subscriptions.pop(args.integer("sub", low=0, high=2**63), None)
        if subscription is not None:
            self._cancel(subscription)

    def _cancel(self, subscription: ActiveSubscription) -> None:
        subscription.queue.close()  # at once: the stepping thread stops queueing for it
        try:
            self._world.submit(subscription.handle.cancel)
        except Exception as exc:  # closed or flooded world: the closed queue ignores it
            logger.debug("could not cancel %s: %s", subscription.topic, exc)

    def drop(self, stream: Stream, reason: str | None) -> None:
        """Forget ``stream`` and cancel its subscriptions; log ``reason`` if not asked for."""
        stream.closed = True
        self._by_peer.pop(stream.peer, None)
        self._by_token.pop(stream.token, None)
        for subscription in stream.subscriptions.values():
            self._cancel(subscription)
        if reason is not None:
            logger.warning(
                "a client stream %s; dropped its %d subscription(s)",
                reason,
                len(stream.subscriptions),
            )
        stream.subscriptions.clear()

    def flush(self) -> None:
        """Send what the subscriptions queued, in batches, as far as each client keeps up."""
        for stream in self.streams:
            if stream.held is not None:
                if not self._send(stream, stream.held):
                    continue
                stream.held = None
            while not stream.closed:
                items = stream.take_batch(MAX_BATCH)
                if not items:
                    self._end_gone(stream)
                    break
                if not self._send(stream, pack({"kind": FrameKind.MESSAGES.value, "items": items})):
                    break

    def _end_gone(self, stream: Stream) -> None:
        """Tell ``stream`` which of its topics went away (once their last messages are
        sent), and drop those subscriptions."""
        for key, subscription in tuple(stream.subscriptions.items()):
            reason = subscription.queue.gone
            if reason is None or len(subscription.queue):
                continue
            if stream.closed or stream.held is not None:
                return  # the rest next time (a busy stream holds one frame at a time)
            del stream.subscriptions[key]
            self._cancel(subscription)
            # Sent, or held and sent before anything else.
            self._send(stream, pack({"kind": FrameKind.ENDED.value, "sub": key, "reason": reason}))

    def tick(self) -> None:
        """Tell every stream the world is alive (and find the clients that are gone)."""
        frame = pack({"kind": FrameKind.TICK.value})
        for stream in self.streams:
            if stream.held is None:
                self._send(stream, frame)

    def close(self, reason: str) -> None:
        """Tell every stream the world is going away and cancel all subscriptions."""
        frame = pack({"kind": FrameKind.CLOSING.value, "reason": reason})
        for stream in self.streams:
            self._outbox.send(stream.peer, frame)
            self.drop(stream, None)

    def _send(self, stream: Stream, frame: bytes) -> bool:
        delivery = self._outbox.send(stream.peer, frame)
        if delivery is Delivery.BUSY:
            stream.held = frame  # and meanwhile its queues drop their oldest messages
        elif delivery is Delivery.GONE:
            self.drop(stream, "went away")
        return delivery is Delivery.SENT
