"""A wall-clock limit on a run, enforced inside the process that runs it.

The limit is a ``SIGALRM`` timer: Python raises :class:`RunTimedOut` in the running
task at its next bytecode, wherever it is (a loop, a ``sleep``, a long ``world.run``).
It derives from ``BaseException``, so a task's ``except Exception`` cannot swallow it.
Only the main thread receives signals (Ray runs tasks there); elsewhere the limit is
not enforced here and the sweep's driver is the backstop (it kills the worker).
A task stuck inside one C call that never returns is also left to that backstop.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType, TracebackType


class RunTimedOut(BaseException):
    """The run was still going when its time was up."""

    def __init__(self, seconds: float) -> None:
        super().__init__(f"the run took longer than its limit of {seconds:g} s (run_timeout_s)")


class RunTimeout:
    """``with RunTimeout(seconds):`` raises :class:`RunTimedOut` in the block after
    ``seconds`` of wall time; :meth:`cancel` ends the limit early (before cleanup that
    must not be cut short)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self._armed = False
        self._previous: object = None

    def __enter__(self) -> RunTimeout:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGALRM, self._expired)
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
            self._armed = True
        return self

    def _expired(self, signum: int, frame: FrameType | None) -> None:
        del signum, frame
        if self._armed:
            raise RunTimedOut(self.seconds)

    def cancel(self) -> None:
        """Stop the timer (idempotent)."""
        if self._armed:
            self._armed = False
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            signal.signal(signal.SIGALRM, self._previous)  # type: ignore[arg-type]

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.cancel()
