"""Everything the server sends goes through here: replies and stream frames, never blocking.

Replies are never dropped silently. A reply ZeroMQ cannot take now (the client
sends faster than it reads) is held, with the client's later replies queued
behind it, and sent as the client reads. Only past :data:`MAX_HELD_REPLY_BYTES`
per client are replies dropped, and then the client is told how many in a reply
with no id once it catches up.
"""

from __future__ import annotations

import enum
import errno
import logging
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import zmq

from armfleet.errors import ArmfleetError
from armfleet.services.codec import pack, to_wire
from armfleet.services.errors import error_fields
from armfleet.services.protocol import MAX_HELD_REPLY_BYTES, FrameKind

logger = logging.getLogger("armfleet")


class Delivery(enum.Enum):
    """What became of a frame."""

    SENT = "sent"
    BUSY = "busy"  # the client's queue is full: it reads too slowly
    GONE = "gone"  # the client has disconnected


@dataclass
class _Backlog:
    """Replies of one client that ZeroMQ could not take yet, oldest first."""

    frames: deque[bytes] = field(default_factory=deque)
    size: int = 0  # [bytes]
    dropped: int = 0  # replies dropped past the limit, not told yet


class Outbox:
    """Non-blocking sends on the server's ROUTER socket (server thread only).

    Args:
        socket: a ROUTER socket with ``ROUTER_MANDATORY`` set, so that a full or
            vanished peer is reported instead of silently dropped.
    """

    def __init__(self, socket: zmq.Socket[bytes]) -> None:
        self._socket = socket
        self._backlogs: dict[bytes, _Backlog] = {}

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
        """Reply with ``error``: an ArmfleetError's own message (and the fields a client
        rebuilds it from, see :func:`~armfleet.services.errors.error_fields`), else an
        internal error."""
        details: dict[str, Any]
        if isinstance(error, ArmfleetError):
            details = {"type": type(error).__name__, "message": str(error)}
            fields = error_fields(error)
            if fields is not None:
                details["fields"] = fields
        else:
            message = f"internal error: {type(error).__name__}: {error}"
            details = {"type": "InternalError", "message": message}
        frame = {"kind": FrameKind.REPLY.value, "id": request_id, "ok": False}
        self._send_reply(peer, frame | {"error": details})

    def held(self, peer: bytes) -> int:
        """Replies to ``peer`` waiting for it to read."""
        backlog = self._backlogs.get(peer)
        return 0 if backlog is None else len(backlog.frames)

    @property
    def holding(self) -> bool:
        """Whether any reply waits for its client to read."""
        return bool(self._backlogs)

    def flush(self) -> list[bytes]:
        """Send the held replies, each client's in order, as far as each reads; return the
        clients found gone (their replies are forgotten)."""
        gone = []
        for peer, backlog in tuple(self._backlogs.items()):
            if not self._drain(peer, backlog):
                gone.append(peer)
        return gone

    def forget(self, peer: bytes) -> None:
        """Drop what is held for ``peer`` (it has disconnected)."""
        self._backlogs.pop(peer, None)

    def _send_reply(self, peer: bytes, reply: dict[str, Any]) -> None:
        frame = pack(reply)
        backlog = self._backlogs.get(peer)
        if backlog is None:
            delivery = self.send(peer, frame)
            if delivery is Delivery.GONE:
                logger.debug("dropped a reply: the client went away")
            if delivery is not Delivery.BUSY:
                return
            backlog = self._backlogs[peer] = _Backlog()
        if backlog.size + len(frame) > MAX_HELD_REPLY_BYTES:
            backlog.dropped += 1
            if backlog.dropped == 1:
                logger.warning(
                    "a client sends requests faster than it reads the replies; dropping "
                    "replies past %d bytes (it will be told how many)",
                    MAX_HELD_REPLY_BYTES,
                )
            return
        backlog.frames.append(frame)
        backlog.size += len(frame)

    def _drain(self, peer: bytes, backlog: _Backlog) -> bool:
        """Send ``peer``'s held replies until it stops reading; False if it is gone."""
        while backlog.frames or backlog.dropped:
            notice = not backlog.frames  # all held replies sent: now say how many were dropped
            frame = pack(_dropped_notice(backlog.dropped)) if notice else backlog.frames[0]
            delivery = self.send(peer, frame)
            if delivery is Delivery.GONE:
                del self._backlogs[peer]
                return False
            if delivery is Delivery.BUSY:
                return True
            if notice:
                backlog.dropped = 0
            else:
                backlog.frames.popleft()
                backlog.size -= len(frame)
        del self._backlogs[peer]
        return True


def _dropped_notice(count: int) -> dict[str, Any]:
    """The reply (with no id) that tells a client ``count`` of its replies were dropped."""
    message = (
        f"{count} replies to this client were dropped: it sent requests faster than it read "
        f"the replies (more than {MAX_HELD_REPLY_BYTES} bytes of them waiting); read each "
        "reply before sending many more"
    )
    error = {"type": "RepliesDropped", "message": message}
    return {"kind": FrameKind.REPLY.value, "id": None, "ok": False, "error": error}
