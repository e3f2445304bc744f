"""Everything the server sends goes through here: replies and stream frames, never blocking."""

from __future__ import annotations

import enum
import errno
import logging
from typing import Any

import zmq

from armfleet.errors import ArmfleetError
from armfleet.remote.codec import pack, to_wire
from armfleet.remote.protocol import FrameKind

logger = logging.getLogger("armfleet")


class Delivery(enum.Enum):
    """What became of a frame."""

    SENT = "sent"
    BUSY = "busy"  # the client's queue is full: it reads too slowly
    GONE = "gone"  # the client has disconnected


class Outbox:
    """Non-blocking sends on the server's ROUTER socket (server thread only).

    Args:
        socket: a ROUTER socket with ``ROUTER_MANDATORY`` set, so that a full or
            vanished peer is reported instead of silently dropped.
    """

    def __init__(self, socket: zmq.Socket[bytes]) -> None:
        self._socket = socket

    def send(self, peer: bytes, frame: bytes) -> Delivery:
        try:
            self._socket.send_multipart([peer, frame], zmq.NOBLOCK)
        except zmq.Again:
            return Delivery.BUSY
        except zmq.ZMQError as exc:
            if exc.errno != errno.EHOSTUNREACH:
                raise
            return Delivery.GONE
        return Delivery.SENT

    def reply(self, peer: bytes, request_id: int | None, result: Any) -> None:
        frame = {"kind": FrameKind.REPLY.value, "id": request_id, "ok": True}
        self._send_reply(peer, frame | {"result": to_wire(result)})

    def reply_error(self, peer: bytes, request_id: int | None, error: BaseException) -> None:
        """Reply with ``error``: an ArmfleetError's own message, else an internal error."""
        if isinstance(error, ArmfleetError):
            kind, message = type(error).__name__, str(error)
        else:
            kind, message = "InternalError", f"internal error: {type(error).__name__}: {error}"
        frame = {"kind": FrameKind.REPLY.value, "id": request_id, "ok": False}
        self._send_reply(peer, frame | {"error": {"type": kind, "message": message}})

    def _send_reply(self, peer: bytes, reply: dict[str, Any]) -> None:
        delivery = self.send(peer, pack(reply))
        if delivery is Delivery.BUSY:
            logger.info("dropped a reply: the client does not read its replies")
        elif delivery is Delivery.GONE:
            logger.debug("dropped a reply: the client went away")
