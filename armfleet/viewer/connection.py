"""A request socket to the viewer server on which every request times out.

It is also the "window" of a ``meshcat.Visualizer`` (``Visualizer(window=...)``):
MeshCat and Pinocchio send their commands through :meth:`BridgeConnection.send`.
One connection belongs to one thread.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import umsgpack
import zmq

from armfleet.viewer.errors import ViewerError, ViewerTimeout

REQUEST_TIMEOUT_S = 5.0


class BridgeConnection:
    """ZMQ REQ socket to the bridge.

    Args:
        context: the viewer's ZMQ context.
        url: ``tcp://127.0.0.1:<port>`` of the bridge.
        web_url: the page, for ``meshcat.Visualizer.url()``.
        timeout_s: default time a request may take [s].
    """

    def __init__(
        self, context: Any, url: str, web_url: str, timeout_s: float = REQUEST_TIMEOUT_S
    ) -> None:
        self._context = context
        self._url = url
        self.web_url = web_url
        self._timeout_s = timeout_s
        self._socket: Any = None
        self._connect()

    def _connect(self) -> None:
        self._socket = self._context.socket(zmq.REQ)
        self._socket.setsockopt(zmq.LINGER, 0)
        # Queue only to a live connection, and never wait forever to send.
        self._socket.setsockopt(zmq.IMMEDIATE, 1)
        self._socket.setsockopt(zmq.SNDTIMEO, round(1000 * self._timeout_s))
        self._socket.connect(self._url)

    def request(self, frames: Sequence[bytes], timeout_s: float | None = None) -> list[bytes]:
        """Send ``frames``, return the reply's frames.

        Raises:
            ViewerTimeout: no reply in time; the socket is reset for the next request.
            ViewerError: the connection is closed or the server refused the request.
        """
        if self._socket is None:
            raise ViewerError("the viewer connection is closed")
        timeout_ms = round(1000 * (timeout_s or self._timeout_s))
        socket = self._socket
        name = frames[0].decode(errors="replace")
        try:
            socket.send_multipart(list(frames), copy=False)
            if not socket.poll(timeout_ms, zmq.POLLIN):
                # A REQ socket without its reply cannot send again: start afresh.
                socket.close()
                self._connect()
                raise ViewerTimeout(name, timeout_ms / 1000)
            reply: list[bytes] = socket.recv_multipart()
        except zmq.Again:
            raise ViewerTimeout(name, self._timeout_s) from None
        except zmq.ZMQError as exc:
            raise ViewerError(f"viewer connection failed: {exc}") from exc
        if reply and reply[0].startswith(b"error"):
            raise ViewerError(f"viewer server: {reply[0].decode(errors='replace')}")
        return reply

    def send(self, command: Any) -> None:
        """Send one MeshCat command (anything with ``lower()``: SetObject, SetTransform, ...)."""
        data = command.lower()
        self.request([data["type"].encode(), data["path"].encode(), umsgpack.packb(data)])

    def close(self) -> None:
        if self._socket is not None:
            self._socket.close()
            self._socket = None
