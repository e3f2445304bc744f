"""Which clients of the server's ROUTER socket have disconnected.

ZeroMQ does not tell a ROUTER socket that a peer left (``ROUTER_NOTIFY`` is a
draft option, absent from the released library). Its socket monitor does report
each TCP connection closing, by file descriptor, and each received message
carries the descriptor it came on (``SRCFD``). Together they name the peers
whose connection closed: a process that exited or was killed, a closed client,
or one the heartbeat found dead. The server then cancels those peers' requests.

A connection's events come in order: its old user's ``DISCONNECTED`` is emitted
before the descriptor is closed, so before it can be reused, so before a new
connection on it is accepted and sends anything. The server therefore reads a
batch of requests, then the monitor's events (:meth:`PeerWatch.departed`), then
notes who sent each request (:meth:`PeerWatch.note`): a descriptor reused by a
new connection is never taken for the old one's.
"""

from __future__ import annotations

import logging
from collections import deque

import zmq
from zmq.utils.monitor import recv_monitor_message

logger = logging.getLogger("armfleet")

#: Departed peers remembered, so that their last requests, read late, are ignored.
REMEMBERED_DEPARTURES = 4096


class PeerWatch:
    """Follows the connections of ``socket`` (server thread only).

    Args:
        socket: the server's ROUTER socket; call :meth:`close` before closing it.
    """

    def __init__(self, socket: zmq.Socket[bytes]) -> None:
        self._socket = socket
        self.monitor: zmq.Socket[bytes] = socket.get_monitor_socket(zmq.EVENT_DISCONNECTED)
        self._peers_by_fd: dict[int, set[bytes]] = {}
        self._departed: set[bytes] = set()
        self._departed_order: deque[bytes] = deque()

    def note(self, peer: bytes, frame: zmq.Frame) -> None:
        """``peer`` sent ``frame``: remember which connection it uses."""
        try:
            fd = int(frame.get(zmq.SRCFD))
        except (zmq.ZMQError, AttributeError, TypeError, ValueError):  # not TCP, or no SRCFD
            return
        if fd >= 0:
            self._peers_by_fd.setdefault(fd, set()).add(peer)

    def has_departed(self, peer: bytes) -> bool:
        return peer in self._departed

    def departed(self) -> list[bytes]:
        """The peers whose connection closed since the last call (reads the monitor)."""
        gone: list[bytes] = []
        while True:
            try:
                event = recv_monitor_message(self.monitor, zmq.NOBLOCK)
            except zmq.Again:
                return gone
            for peer in self._peers_by_fd.pop(int(event["value"]), set()):
                self._remember(peer)
                gone.append(peer)

    def _remember(self, peer: bytes) -> None:
        self._departed.add(peer)
        self._departed_order.append(peer)
        if len(self._departed_order) > REMEMBERED_DEPARTURES:
            self._departed.discard(self._departed_order.popleft())

    def close(self) -> None:
        try:
            self._socket.disable_monitor()
        except zmq.ZMQError as exc:  # the socket is closing already
            logger.debug("could not stop the socket monitor: %s", exc)
        self.monitor.close(linger=0)
