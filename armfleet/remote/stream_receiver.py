"""The client's stream: a thread that receives topic messages and calls the callbacks.

It reads everything ZeroMQ has before it calls anyone, into bounded per-subscription
queues (drop oldest), so a slow callback sees fresh messages rather than a backlog.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import zmq

from armfleet.services.codec import decode_message, pack, unpack
from armfleet.services.errors import ConnectionLost, NoWorldFound, TopicGone
from armfleet.services.protocol import STREAM_SILENCE_S, FrameKind

logger = logging.getLogger("armfleet")

#: Longest time spent calling callbacks before reading the socket again [s].
DISPATCH_SLICE_S = 0.01
#: Frames ZeroMQ buffers for this client; the world drops the oldest messages beyond.
RECEIVE_HWM = 16


class LocalSubscription:
    """Client-side state of one subscription (shared with the receiving thread)."""

    def __init__(self, key: int, topic: str, callback: Callable[[Any], None], size: int) -> None:
        self.key = key
        self.topic = topic
        self.callback = callback
        self.items: deque[Any] = deque(maxlen=size)
        self.received = 0
        self.dropped_here = 0
        self.dropped_by_world = 0
        self.error: BaseException | None = None
        self.ended = threading.Event()

    def end(self, error: BaseException | None) -> None:
        if not self.ended.is_set():
            self.error = error
            self.ended.set()


class StreamReceiver:
    """The stream socket of a client and the thread that owns it.

    Args:
        owner: the key ``hello`` returned on the client's request connection: the stream
            is then theirs alone (see :mod:`armfleet.remote.streams`).

    Raises:
        NoWorldFound: the world did not accept the stream within ``timeout`` [s].
    """

    def __init__(
        self,
        context: zmq.Context[zmq.Socket[bytes]],
        address: str,
        timeout: float,
        owner: str | None = None,
    ) -> None:
        self._context = context
        self._owner = owner
        self._address = address
        self._subscriptions: dict[int, LocalSubscription] = {}
        self._keys = itertools.count(1)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._attached = threading.Event()
        self.token = ""
        self.lost: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="armfleet-stream", daemon=True)
        self._thread.start()
        if not self._attached.wait(timeout):
            self.close()
            raise NoWorldFound(f"the world at {address} did not open a stream within {timeout:g} s")

    def add(self, topic: str, callback: Callable[[Any], None], size: int) -> LocalSubscription:
        with self._lock:
            subscription = LocalSubscription(next(self._keys), topic, callback, size)
            self._subscriptions[subscription.key] = subscription
        return subscription

    def remove(self, key: int) -> None:
        with self._lock:
            subscription = self._subscriptions.pop(key, None)
        if subscription is not None:
            subscription.end(None)

    def close(self) -> None:
        self._stop.set()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout=2.0)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    # -- the receiving thread ---------------------------------------------------------
    def _run(self) -> None:
        socket = self._context.socket(zmq.DEALER)
        socket.setsockopt(zmq.LINGER, 0)
        socket.setsockopt(zmq.RCVHWM, RECEIVE_HWM)
        socket.connect(self._address)
        attach = {} if self._owner is None else {"owner": self._owner}
        socket.send(pack({"id": 0, "op": "attach", "args": attach}), zmq.NOBLOCK)
        last_heard = time.monotonic()
        try:
            while not self._stop.is_set():
                if socket.poll(100 if not self._backlog() else 0):
                    while True:
                        try:
                            frame = socket.recv(zmq.NOBLOCK)
                        except zmq.Again:
                            break
                        last_heard = time.monotonic()
                        self._on_frame(frame)
                if self.lost is not None:
                    break
                if self._attached.is_set() and time.monotonic() - last_heard > STREAM_SILENCE_S:
                    self._lose(ConnectionLost(f"the world at {self._address} stopped answering"))
                    break
                self._dispatch()
        except Exception as exc:
            logger.exception("the stream from %s failed", self._address)
            self._lose(ConnectionLost(f"the stream from {self._address} failed: {exc}"))
        finally:
            if self.lost is None and self.token:
                with contextlib.suppress(zmq.ZMQError):
                    socket.send(pack({"id": 0, "op": "detach", "args": {}}), zmq.NOBLOCK)
            socket.close(linger=100 if self.lost is None else 0)

    def _on_frame(self, data: bytes) -> None:
        frame = unpack(data)
        kind = frame.get("kind") if isinstance(frame, dict) else None
        if kind == FrameKind.MESSAGES.value:
            with self._lock:
                subscriptions = self._subscriptions
                for key, dropped, type_name, message in frame["items"]:
                    subscription = subscriptions.get(key)
                    if subscription is None:
                        continue  # cancelled meanwhile
                    subscription.dropped_by_world = dropped
                    if len(subscription.items) == subscription.items.maxlen:
                        subscription.dropped_here += 1
                    subscription.items.append((type_name, message))
        elif kind == FrameKind.REPLY.value and not self._attached.is_set():
            result = frame.get("result")
            if frame.get("ok") and isinstance(result, dict):
                self.token = str(result["stream"])
                self._attached.set()
            else:
                self._lose(ConnectionLost(f"the world refused a stream: {frame.get('error')}"))
        elif kind == FrameKind.ENDED.value:
            with self._lock:
                subscription = self._subscriptions.get(frame.get("sub"))
            if subscription is not None:  # its queued messages are still delivered
                subscription.end(TopicGone(subscription.topic, str(frame.get("reason", ""))))
        elif kind == FrameKind.CLOSING.value:
            self._lose(ConnectionLost(f"the world at {self._address} closed"))

    def _backlog(self) -> bool:
        return any(s.items for s in tuple(self._subscriptions.values()))

    def _dispatch(self) -> None:
        started = time.monotonic()
        while time.monotonic() - started < DISPATCH_SLICE_S:
            delivered = False
            for subscription in tuple(self._subscriptions.values()):
                try:
                    type_name, message = subscription.items.popleft()
                except IndexError:
                    continue
                delivered = True
                subscription.received += 1
                try:
                    subscription.callback(decode_message(type_name, message))
                except Exception:
                    logger.exception("subscriber callback for %s failed", subscription.topic)
            if not delivered:
                return

    def _lose(self, error: BaseException) -> None:
        self.lost = error
        with self._lock:
            for subscription in self._subscriptions.values():
                subscription.end(error)
