"""A few threads beside the stepping thread, for work that must not hold it (planning).

Work handed to :class:`WorkerThreads` runs on one of at most ``count`` daemon threads,
started on first use; more work waits its turn in order. The work must not touch the
world (it hands results back with ``world.submit``). The threads are daemons: a program
that ends while a long search runs is not kept alive by it.
"""

from __future__ import annotations

import contextlib
import queue
import threading
from collections.abc import Callable
from concurrent.futures import CancelledError, Future, InvalidStateError
from typing import Any, TypeVar

T = TypeVar("T")


class WorkerThreads:
    """Up to ``count`` daemon threads named ``name``, running submitted functions in order.

    Args:
        name: the threads' name (``armfleet-planning``), for debuggers and tests.
        count: threads at most; at least 1.
    """

    def __init__(self, name: str, count: int) -> None:
        if count < 1:
            raise ValueError(f"WorkerThreads needs at least 1 thread, got {count}")
        self._name = name
        self._count = count
        self._work: queue.SimpleQueue[tuple[Callable[[], Any], Future[Any]] | None] = (
            queue.SimpleQueue()
        )
        self._threads: list[threading.Thread] = []
        #: Threads waiting for work, and work waiting for a thread.
        self._idle = self._queued = 0
        self._lock = threading.Lock()
        self._closed = False

    def submit(self, function: Callable[[], T]) -> Future[T]:
        """Run ``function`` on a worker thread; its result or exception lands in the future.

        Raises:
            RuntimeError: after :meth:`close`.
        """
        future: Future[T] = Future()
        with self._lock:
            if self._closed:
                raise RuntimeError("the worker threads are closed")
            self._work.put((function, future))
            self._queued += 1
            if self._queued > self._idle and len(self._threads) < self._count:
                thread = threading.Thread(target=self._run, name=self._name, daemon=True)
                self._threads.append(thread)
                thread.start()
        return future

    @property
    def threads(self) -> int:
        """Threads started so far."""
        return len(self._threads)

    def close(self) -> None:
        """Cancel the work not started; the threads stop once their current work is done."""
        with self._lock:
            self._closed = True
            while True:
                try:
                    item = self._work.get_nowait()
                except queue.Empty:
                    break
                if item is not None:
                    item[1].cancel()
            for _ in self._threads:
                self._work.put(None)

    def _run(self) -> None:
        while True:
            with self._lock:
                self._idle += 1
            item = self._work.get()
            with self._lock:
                self._idle -= 1
                self._queued -= item is not None
            if item is None:
                return
            function, future = item
            if future.set_running_or_notify_cancel():
                try:
                    result = function()
                except BaseException as exc:  # the submitter gets it; the thread goes on
                    with contextlib.suppress(InvalidStateError):
                        future.set_exception(exc)
                else:
                    with contextlib.suppress(InvalidStateError, CancelledError):
                        future.set_result(result)
