"""A wall-clock limit on a run, enforced inside the process that runs it.

The limit is wall time, not simulated time or CPU time: on a loaded machine a run that
normally finishes well within it can reach it, and a seed that was a row of metrics
becomes a failed row ``RunTimedOut``. The task has the limit to itself; the world's
bring-up before it has a limit of the same length of its own, so a slow bring-up never
shortens the task's time.

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

#: How a failed row ended by its time limit starts its ``error``.
TIMED_OUT = "RunTimedOut"


class RunTimedOut(BaseException):
    """The run was still going when its time was up."""

    def __init__(self, seconds: float, what: str = "task") -> None:
        super().__init__(
            f"the run's {what} took longer than its limit of {seconds:g} s of wall time "
            "(run_timeout_s)"
        )


class RunTimeout:
    """``with RunTimeout(seconds):`` raises :class:`RunTimedOut` in the block after
    ``seconds`` of wall time; :meth:`cancel` ends the limit early (before cleanup that
    must not be cut short).

    Args:
        seconds: the limit [s of wall time].
        what: the part of the run it limits, for the message (``task``, ``bring-up``).
    """

    def __init__(self, seconds: float, what: str = "task") -> None:
        self.seconds = seconds
        self.what = what
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
            raise RunTimedOut(self.seconds, self.what)

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
