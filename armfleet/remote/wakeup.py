"""A wake-up signal other threads give a thread waiting in ``zmq.Poller``."""

from __future__ import annotations

import contextlib
import socket
import threading


class Wakeup:
    """A socket pair: :meth:`signal` from any thread makes :attr:`fileno` readable.

    Signals coalesce: many calls before :meth:`clear` cost one byte.
    """

    def __init__(self) -> None:
        self._reader, self._writer = socket.socketpair()
        self._reader.setblocking(False)
        self._writer.setblocking(False)
        self._pending = False
        self._lock = threading.Lock()

    def fileno(self) -> int:
        return self._reader.fileno()

    def signal(self) -> None:
        if self._pending:
            return
        with self._lock:
            if self._pending:
                return
            self._pending = True
            with contextlib.suppress(OSError):  # already readable, or closing
                self._writer.send(b"\x01")

    def clear(self) -> None:
        """Forget the signals so far (call before doing the work they announce)."""
        with self._lock:
            self._pending = False
            with contextlib.suppress(OSError):  # BlockingIOError: nothing left to read
                while self._reader.recv(4096):
                    pass

    def close(self) -> None:
        self._reader.close()
        self._writer.close()
