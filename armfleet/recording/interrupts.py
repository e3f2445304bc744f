"""Hold Ctrl-C (SIGINT) and SIGTERM while a file is in a state that must not be cut.

A ``KeyboardInterrupt`` can surface between any two bytecodes of the main
thread; raised inside the MCAP writer it would leave a half-written record
that the final summary then points into. Inside :func:`deferred_interrupts`
such a signal is noted, and delivered to the handler that was in place once
the block is done.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any

SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextmanager
def deferred_interrupts() -> Iterator[None]:
    """Run the block without being interrupted by SIGINT or SIGTERM, then deliver them.

    Only the main thread receives Python signal handlers, so elsewhere this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[tuple[int, FrameType | None]] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        caught.append((signum, frame))

    previous: dict[int, Any] = {}
    try:
        for held in SIGNALS:
            handler = signal.getsignal(held)
            if handler is not None:  # None: installed outside Python; leave it alone
                previous[held] = signal.signal(held, hold)
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for signum, frame in caught:
            _deliver(previous[signum], signum, frame)


def _deliver(
    handler: Callable[[int, FrameType | None], Any] | int, signum: int, frame: Any
) -> None:
    if callable(handler):
        handler(signum, frame)
    elif handler == signal.SIG_DFL:
        signal.raise_signal(signum)
