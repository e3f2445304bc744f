"""What the loop stepping a world and the API server share: pause, wake-ups, measured RTF."""

from __future__ import annotations

import threading
import time
from collections import deque

#: Window over which the real-time factor is measured [s of wall time].
RTF_WINDOW_S = 2.0


class RunState:
    """Run control of one world's stepping loop, safe to use from any thread.

    The loop calls :meth:`note_progress` as it steps and checks :attr:`paused`
    before every step; while paused it keeps calling ``world.process_requests()``
    and :meth:`sleep` so that requests are still served. The API server pauses
    and resumes through requests run in the stepping thread, so a pause takes
    effect exactly at a step boundary, and :meth:`wake` s the loop when it hands
    over work so a sleeping loop serves it at once.
    """

    def __init__(self) -> None:
        self._paused = False
        self._wake = threading.Event()
        self._samples: deque[tuple[float, float]] = deque()
        self._lock = threading.Lock()

    @property
    def paused(self) -> bool:
        return self._paused

    def pause(self) -> None:
        self._paused = True

    def resume(self) -> None:
        self._paused = False
        with self._lock:
            self._samples.clear()  # the paused time is not slowness
        self._wake.set()

    def wake(self) -> None:
        """Cut the loop's current :meth:`sleep` short (work was handed over)."""
        self._wake.set()

    def sleep(self, seconds: float) -> None:
        """Sleep up to ``seconds`` [s], less if :meth:`wake` is called meanwhile."""
        if seconds > 0 and self._wake.wait(seconds):
            self._wake.clear()

    def note_progress(self, sim_time: float, wall_time: float | None = None) -> None:
        """Record that the world reached ``sim_time`` [s] at ``wall_time`` (monotonic) [s]."""
        now = time.monotonic() if wall_time is None else wall_time
        with self._lock:
            samples = self._samples
            samples.append((sim_time, now))
            while len(samples) > 2 and now - samples[1][1] >= RTF_WINDOW_S:
                samples.popleft()

    @property
    def realtime_factor(self) -> float | None:
        """Simulated over wall time in the last couple of seconds; 0 when paused;
        None before the loop has reported progress."""
        if self._paused:
            return 0.0
        with self._lock:
            if len(self._samples) < 2:
                return None
            (sim0, wall0), (sim1, wall1) = self._samples[0], self._samples[-1]
        return (sim1 - sim0) / (wall1 - wall0) if wall1 > wall0 else None
