"""The client's request socket: one request, one reply, every wait bounded."""

from __future__ import annotations

import itertools
import threading
import time
from typing import Any

import zmq

from armfleet.services.codec import pack, unpack
from armfleet.services.errors import ConnectionLost, RemoteError, RequestTimeout, remote_error
from armfleet.services.protocol import FrameKind

#: Share of a request's timeout the world may keep it queued before refusing it,
#: so that its refusal arrives before the client gives up.
QUEUE_SHARE = 0.8


class RequestChannel:
    """A DEALER socket to a world, safe to share between threads (calls take turns).

    Args:
        context: the client's ZeroMQ context.
        address: ``tcp://HOST:PORT`` of the world.
    """

    def __init__(self, context: zmq.Context[zmq.Socket[bytes]], address: str) -> None:
        self.address = address
        self._socket = context.socket(zmq.DEALER)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.connect(address)
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._closed = False

    def call(
        self, op: str, args: dict[str, Any] | None, timeout: float, work_s: float = 0.0
    ) -> Any:
        """Send request ``op`` and return its result.

        Args:
            timeout: wait for the world to take the request up and answer [s]; the
                world refuses it, unapplied, if it has not started it within
                :data:`QUEUE_SHARE` of this.
            work_s: how long the work itself may take once started (a plan's time
                budget) [s], waited for on top of ``timeout``.

        Raises:
            RemoteError: the world refused it (its message says why).
            RequestTimeout: no reply within ``timeout + work_s`` [s].
        """
        with self._lock:
            if self._closed:
                raise ConnectionLost("this client is closed")
            request_id = next(self._ids)
            frame = {
                "id": request_id,
                "op": op,
                "args": args or {},
                "timeout_s": timeout * QUEUE_SHARE,
            }
            # The queue share is of ``timeout`` alone: work that starts late must still
            # have its whole budget before this side gives up on it.
            wait = timeout + work_s
            deadline = time.monotonic() + wait
            try:
                self._socket.send(pack(frame), zmq.NOBLOCK)
            except zmq.Again:
                raise RequestTimeout(
                    f"{op}: cannot reach the world at {self.address} (is it running?)"
                ) from None
            while True:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or not self._socket.poll(max(1, round(remaining * 1000))):
                    raise RequestTimeout(
                        f"{op}: no answer from the world at {self.address} within {wait:g} s"
                        + ("" if op in _READ_ONLY else "; it may still be applied")
                    )
                reply = unpack(self._socket.recv())
                if isinstance(reply, dict) and reply.get("id") == request_id:
                    return _result(reply)
                # else: the late reply of a request that timed out; skip it

    def close(self) -> None:
        with self._lock:
            self._closed = True
            self._socket.close(linger=0)


_READ_ONLY = {"hello", "info", "arms", "arm", "joint_state", "topics", "wait"}


def _result(reply: dict[str, Any]) -> Any:
    if reply.get("kind") != FrameKind.REPLY.value:
        raise RemoteError("ProtocolError", f"unexpected frame from the world: {reply!r:.200}")
    if reply.get("ok") is True:
        return reply.get("result")
    error = reply.get("error")
    if not isinstance(error, dict):
        raise RemoteError("ProtocolError", f"malformed error reply: {reply!r:.200}")
    kind, message = str(error.get("type", "Error")), str(error.get("message", ""))
    raise remote_error(kind, message, error.get("fields"))
