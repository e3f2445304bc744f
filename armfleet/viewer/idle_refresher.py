"""One last display update once the simulation pauses.

Display updates ride on the simulation's ticks. When the ticks stop (``run``
returned, a notebook cell ended) the page would keep the poses of the last
update, up to a frame behind the simulation. This thread sleeps until woken
by a display update, then checks every ``pause_s`` whether the updates
stopped, and if so asks for one more.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

STOP_TIMEOUT_S = 5.0


class IdleRefresher:
    """Background thread behind :meth:`wake`.

    Args:
        pause_s: how long without display updates counts as a pause [s].
        refresh_if_paused: sends the last update and returns True if updates
            have stopped for ``pause_s``; returns False while they go on.
    """

    def __init__(self, pause_s: float, refresh_if_paused: Callable[[], bool]) -> None:
        self._pause_s = pause_s
        self._refresh_if_paused = refresh_if_paused
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="armfleet-viewer", daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """Start watching for a pause (display updates are flowing)."""
        self._wake.set()

    def stop(self) -> None:
        """End the thread; idempotent."""
        self._stop.set()
        self._wake.set()
        if self._thread is not threading.current_thread():
            self._thread.join(STOP_TIMEOUT_S)

    def _run(self) -> None:
        while not self._stop.is_set():
            self._wake.wait()
            self._wake.clear()
            while not self._stop.wait(self._pause_s):
                if self._refresh_if_paused():
                    break
