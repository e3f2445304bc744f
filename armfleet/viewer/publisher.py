"""Sends live updates to the viewer server from a background thread.

The simulation hands over its latest updates and goes on at once
(:meth:`UpdatePublisher.offer`); the thread sends them one batch (one
request) at a time. Updates that pile up while a batch is in flight are
merged, newest value per node, so a slow server or browser costs frames,
never simulation time. Once offers stop (the simulation paused), the thread
asks for one last refresh so the browser shows where the arms came to rest.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from armfleet.viewer.commands import Updates
from armfleet.viewer.connection import REQUEST_TIMEOUT_S, BridgeConnection
from armfleet.viewer.errors import ViewerError

#: Longer than a request may take, so that a stopped thread has let go of its socket.
STOP_TIMEOUT_S = REQUEST_TIMEOUT_S + 2.0


class UpdatePublisher:
    """Background sender of live updates.

    Args:
        connect: opens the thread's own connection to the server.
        on_error: told about a failed request; returns whether to go on.
        idle_s: time without offers after which ``on_idle`` is asked for updates [s].
        on_idle: returns the updates that bring the browser up to date.
    """

    def __init__(
        self,
        connect: Callable[[], BridgeConnection],
        on_error: Callable[[ViewerError], bool],
        idle_s: float,
        on_idle: Callable[[], Updates],
    ) -> None:
        self._connect = connect
        self._on_error = on_error
        self._idle_s = idle_s
        self._on_idle = on_idle
        self._refresh_due = False
        self._pending: Updates = {}
        self._sending = False
        self._stopped = False
        self._condition = threading.Condition()
        self._batches_sent = 0
        self._thread = threading.Thread(target=self._run, name="armfleet-viewer", daemon=True)
        self._thread.start()

    @property
    def batches_sent(self) -> int:
        """Requests the server has answered."""
        return self._batches_sent

    def offer(self, updates: Updates) -> None:
        """Queue ``updates`` (replacing older ones of the same nodes); returns at once."""
        with self._condition:
            self._pending.update(updates)
            self._refresh_due = True
            self._condition.notify()

    def discard(self, path_prefix: str, timeout_s: float = STOP_TIMEOUT_S) -> None:
        """Forget queued updates under ``path_prefix`` and wait for the batch in flight."""
        prefix = path_prefix.encode()
        with self._condition:
            for key in [k for k in self._pending if k[1].startswith(prefix)]:
                del self._pending[key]
            self._condition.wait_for(lambda: not self._sending, timeout_s)

    def flush(self, timeout_s: float = STOP_TIMEOUT_S) -> bool:
        """Wait until everything queued has been sent; False on timeout or stop."""
        with self._condition:
            return (
                self._condition.wait_for(
                    lambda: self._stopped or not (self._pending or self._sending), timeout_s
                )
                and not self._stopped
            )

    def stop(self) -> None:
        """Stop the thread (queued updates are dropped); idempotent."""
        with self._condition:
            self._stopped = True
            self._condition.notify_all()
        if self._thread is not threading.current_thread():
            self._thread.join(STOP_TIMEOUT_S)

    def _run(self) -> None:
        try:
            connection = self._connect()
        except ViewerError as exc:
            self._on_error(exc)
            self.stop()
            return
        try:
            while self._send_next(connection):
                pass
        finally:
            connection.close()

    def _send_next(self, connection: BridgeConnection) -> bool:
        with self._condition:
            ready = self._condition.wait_for(
                lambda: self._stopped or bool(self._pending),
                self._idle_s if self._refresh_due else None,
            )
            if self._stopped:
                return False
            if not ready:  # offers stopped: one last refresh
                self._refresh_due = False
        if not ready:
            updates = self._on_idle()  # outside the condition: it takes the viewer's lock
            with self._condition:
                for key, data in updates.items():
                    self._pending.setdefault(key, data)
            return True
        with self._condition:
            batch, self._pending = self._pending, {}
            self._sending = True
        index: list[bytes] = []
        for (kind, path, _), data in batch.items():
            index += (kind, path, b"%d" % len(data))
        frames = [b"batch", b"\0".join(index), b"".join(batch.values())]
        go_on, sent = True, False
        try:
            connection.request(frames)
            sent = True
            self._batches_sent += 1
        except ViewerError as exc:
            go_on = self._on_error(exc)
        finally:
            with self._condition:
                if not sent:  # send it again with the next batch, unless newer
                    for key, data in batch.items():
                        self._pending.setdefault(key, data)
                self._sending = False
                self._stopped = self._stopped or not go_on
                self._condition.notify_all()
        return go_on
