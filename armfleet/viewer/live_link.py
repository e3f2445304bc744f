"""The socket live updates travel on: sending never blocks, never waits for a reply.

The simulation thread sends a display update itself, at once: ZMQ's own I/O
thread (C++, no GIL) carries it to the server. At most
:data:`MAX_IN_FLIGHT` batches are unanswered at any time; while the server
is behind, updates wait in a latest-value slot (newest value per node) and
go with the next batch, so a slow server or browser costs frames, never
simulation time. A Python thread doing the sending instead cost the
simulation ~5 % more CPU with 10 arms, from handing the GIL back and forth.
"""

from __future__ import annotations

import time
from typing import Any

import zmq

from armfleet.viewer.commands import Updates
from armfleet.viewer.errors import ViewerError

#: Batches sent and not yet answered by the server.
MAX_IN_FLIGHT = 2


class LiveLink:
    """A DEALER socket to the bridge for batches of live updates.

    Not thread-safe: the viewer calls it under its lock.

    Args:
        context: the viewer's ZMQ context.
        url: ``tcp://127.0.0.1:<port>`` of the bridge.
    """

    def __init__(self, context: Any, url: str) -> None:
        self._socket = context.socket(zmq.DEALER)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.setsockopt(zmq.IMMEDIATE, 1)  # queue only to a live connection
        self._socket.setsockopt(zmq.SNDHWM, MAX_IN_FLIGHT + 1)
        self._socket.connect(url)
        self._pending: Updates = {}
        self._in_flight = 0
        self._progress_s = time.perf_counter()  # last send or reply
        self._answered = 0
        self._closed = False

    @property
    def batches_answered(self) -> int:
        """Batches the server has acknowledged so far."""
        return self._answered

    @property
    def stalled_s(self) -> float:
        """How long updates have waited without the link moving (no send, no reply) [s].

        0 when nothing waits. A server that keeps up answers within milliseconds.
        """
        if not (self._pending or self._in_flight):
            return 0.0
        return time.perf_counter() - self._progress_s

    def offer(self, updates: Updates) -> None:
        """Merge ``updates`` into the slot and send it if the server keeps up; never blocks."""
        self._pending.update(updates)
        self._collect_replies()
        if self._pending and self._in_flight < MAX_IN_FLIGHT:
            self._send()

    def discard(self, path_prefix: str) -> None:
        """Forget updates of nodes under ``path_prefix`` that were not sent yet."""
        prefix = path_prefix.encode()
        for key in [k for k in self._pending if k[1].startswith(prefix)]:
            del self._pending[key]

    def wait(self, timeout_s: float) -> bool:
        """Send what waits and wait for every reply; False if not done within ``timeout_s``."""
        deadline = time.perf_counter() + timeout_s
        while self._pending or self._in_flight:
            left_ms = round(1000 * (deadline - time.perf_counter()))
            if left_ms <= 0 or self._closed:
                return False
            if self._pending and self._in_flight < MAX_IN_FLIGHT:
                self._send()
            if self._in_flight and self._socket.poll(min(left_ms, 50), zmq.POLLIN):
                self._collect_replies()
        return True

    def _send(self) -> None:
        index: list[bytes] = []
        for (kind, path, _), data in self._pending.items():
            index += (kind, path, b"%d" % len(data))
        frames = [b"", b"batch", b"\0".join(index), b"".join(self._pending.values())]
        try:
            self._socket.send_multipart(frames, zmq.NOBLOCK)
        except zmq.Again:  # not connected, or its queue is full: try with the next update
            return
        self._progress_s = time.perf_counter()
        self._in_flight += 1
        self._pending = {}

    def _collect_replies(self) -> None:
        while self._in_flight:
            try:
                reply = self._socket.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                return
            self._in_flight -= 1
            self._progress_s = time.perf_counter()
            if reply[-1] != b"ok":
                raise ViewerError(f"viewer server: {reply[-1].decode(errors='replace')}")
            self._answered += 1

    def close(self) -> None:
        self._closed = True
        self._socket.close()
