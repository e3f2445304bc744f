"""Work handed to the stepping thread from other threads, run at step boundaries.

The world stays single-threaded: a client thread never touches PyBullet or the
controllers itself; it submits a function and waits on the returned future.

A request whose answer takes longer than a step (a planned move: the search runs on a
worker thread while the world goes on stepping) returns a :class:`Deferred` instead of
its result: its future then completes when the deferred one does, and the queue moves
on at once.
"""

from __future__ import annotations

import contextlib
import functools
import queue
from collections.abc import Callable, Iterator
from concurrent.futures import CancelledError, Future
from typing import Any, TypeVar

T = TypeVar("T")


class Deferred(Future[T]):
    """The answer of a request that is still being worked out elsewhere: returned by a
    submitted function, it completes that request's future when it completes (with its
    result or its exception). Only this class is chained: a plain :class:`Future` a
    function returns is its result, as any other value."""


def _forward(source: Future[Any], target: Future[Any]) -> None:
    """Complete ``target`` as ``source`` completed (a cancelled source fails it)."""
    if source.cancelled():
        target.set_exception(CancelledError())
        return
    error = source.exception()
    if error is not None:
        target.set_exception(error)
    else:
        target.set_result(source.result())


class RequestQueue:
    """A FIFO of functions, drained by the thread that steps the world.

    Args:
        max_pending: requests waiting at most; submitting more raises ``queue.Full``.
    """

    def __init__(self, max_pending: int = 1024) -> None:
        self._pending: queue.Queue[tuple[Callable[[], Any], Future[Any]]] = queue.Queue(max_pending)
        self._draining = False

    def submit(self, function: Callable[[], T]) -> Future[T]:
        """Queue ``function``; its result or exception lands in the returned future."""
        future: Future[T] = Future()
        self._pending.put_nowait((function, future))
        return future

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Run no request inside this block (a bring-up that steps the world itself)."""
        draining, self._draining = self._draining, True
        try:
            yield
        finally:
            self._draining = draining

    def drain(self) -> int:
        """Run every queued function, in order, in the calling thread; return how many ran.

        Requests submitted while draining wait for the next drain, so a flood of
        them cannot stall the world. A request that steps the world itself (a
        spawn's bring-up) does not drain the queue from inside: requests never
        interleave.
        """
        if self._draining:
            return 0
        self._draining = True
        try:
            count = self._pending.qsize()
            for _ in range(count):
                function, future = self._pending.get_nowait()
                if not future.set_running_or_notify_cancel():
                    continue
                try:
                    result = function()
                    if isinstance(result, Deferred):
                        result.add_done_callback(functools.partial(_forward, target=future))
                    else:
                        future.set_result(result)
                except Exception as exc:  # the caller gets it; the world goes on
                    future.set_exception(exc)
                except BaseException as exc:  # Ctrl-C: tell the caller, then stop
                    future.set_exception(exc)
                    raise
            return count
        finally:
            self._draining = False

    def cancel_all(self, reason: BaseException) -> None:
        """Fail every pending request with ``reason`` (the world is closing)."""
        while True:
            try:
                _, future = self._pending.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                future.set_exception(reason)
