"""Who may change a world now: one thread at a time, and never from inside a step.

A :class:`armfleet.World` is single-threaded (PyBullet and the controllers are
not thread-safe) and its step is not reentrant: bus subscribers run in the
middle of it, while the controllers, the contact scan and the status loop are
iterating over the arms. So the calls that step the world or change what is in
it (``step``, ``run``, ``spawn``, ``remove``, ``add_object``, ``remove_object``)
take the world through :meth:`StepGuard.owned`:

- the thread inside them owns the world until the outermost call returns (a
  spawn's bring-up, which steps the world from inside ``spawn``, is that same
  thread going deeper, and allowed);
- another thread is refused with :class:`WorldBusy` (it hands its work to the
  stepping thread with ``world.submit``). Refused, not made to wait: a ``run`` may
  last for hours, and a waiting thread could starve behind a loop of steps. A
  thread that steps in its own loop owns the world only during each step, so a
  direct call from elsewhere may land between two steps and the loop's next step
  is then the one refused: that is why other threads should use ``submit``;
- a call from inside a step (a bus subscriber) is refused with
  :class:`WorldBusy` too: removing an arm while the status loop iterates over
  the arms, or stepping inside a step, broke the step in progress.

``close`` is the one call that is never refused: from another thread or from
inside a step it is put off to the end of the step (:meth:`StepGuard.closing`).
"""

from __future__ import annotations

import contextlib
import functools
import threading
from collections.abc import Callable, Iterator
from typing import Concatenate, ParamSpec, Protocol, TypeVar

from armfleet.errors import WorldBusy


class StepGuard:
    """The owner thread of a world and whether it is inside a step.

    Args:
        close: closes the world; called when the owner lets go and a close was put off.
    """

    def __init__(self, close: Callable[[], None]) -> None:
        self._close = close
        self._lock = threading.Lock()
        self._owner: int | None = None
        self._depth = 0
        self._in_step = False
        self._close_pending = False

    def acquire(self, call: str) -> None:
        """Own the world for ``call`` (e.g. ``"spawn"``) in the calling thread, until
        the matching :meth:`release`.

        Raises:
            WorldBusy: another thread owns it, or the call comes from inside a step.
        """
        me = threading.get_ident()
        with self._lock:
            if self._owner is not None and self._owner != me:
                raise WorldBusy(call, "another thread is stepping or changing this world")
            if self._in_step:
                raise WorldBusy(call, "it was called from inside a step (a bus subscriber)")
            self._owner = me
            self._depth += 1

    def release(self) -> None:
        """End one :meth:`acquire`; the outermost one closes the world if a close was put off."""
        with self._lock:
            self._depth -= 1
            if self._depth == 0:
                self._owner = None
            due = self._depth == 0 and self._close_pending
            self._close_pending = self._close_pending and not due
        if due:
            self._close()

    @contextlib.contextmanager
    def owned(self, call: str) -> Iterator[None]:
        """:meth:`acquire` for ``call`` around a ``with`` block, then :meth:`release`."""
        self.acquire(call)
        try:
            yield
        finally:
            self.release()

    def begin_step(self) -> None:
        """Mark the start of a step's body, where subscribers run and the world must not
        change; :meth:`end_step` ends it. (Two plain calls, not a context manager: this
        runs at every physics step.)"""
        self._in_step = True

    def end_step(self) -> None:
        self._in_step = False

    @contextlib.contextmanager
    def closing(self) -> Iterator[bool]:
        """Own the world to close it now (yields True); or, from inside a step or from
        another thread than the owner, note the close for the owner, who closes the
        world when its outermost call returns or ``run`` reaches a step boundary
        (yields False)."""
        me = threading.get_ident()
        with self._lock:
            now = (self._owner is None or self._owner == me) and not self._in_step
            if now:
                self._owner = me
                self._depth += 1
            else:
                self._close_pending = True
        if not now:
            yield False
            return
        try:
            yield True
        finally:
            with self._lock:
                self._depth -= 1
                if self._depth == 0:
                    self._owner = None
                self._close_pending = False  # closed now

    def take_close(self) -> bool:
        """Whether a put-off ``close`` is due now: asked between steps by the outermost
        owning call (``run``), which then closes the world and returns."""
        with self._lock:
            due = self._close_pending and self._depth == 1 and not self._in_step
            self._close_pending = self._close_pending and not due
            return due


class Guarded(Protocol):
    """Anything with a :class:`StepGuard` (a world)."""

    @property
    def step_guard(self) -> StepGuard: ...


P = ParamSpec("P")
R = TypeVar("R")
G = TypeVar("G", bound=Guarded)


def owning(method: Callable[Concatenate[G, P], R]) -> Callable[Concatenate[G, P], R]:
    """Wrap a world's ``method`` so it runs owning the world (see :meth:`StepGuard.owned`)."""

    call = method.__name__

    @functools.wraps(method)
    def owned(self: G, /, *args: P.args, **kwargs: P.kwargs) -> R:
        guard = self.step_guard
        guard.acquire(call)
        try:
            return method(self, *args, **kwargs)
        finally:
            guard.release()

    return owned
