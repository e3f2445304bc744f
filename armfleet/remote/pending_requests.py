"""Requests handed to the stepping thread and not yet answered.

Limits are per client (per ZeroMQ peer): one client with as many requests
unanswered as its quota (``ClientQuotas.requests_per_client`` of
:mod:`armfleet.remote.client_quotas`,
:data:`~armfleet.services.protocol.MAX_IN_FLIGHT_PER_CLIENT` by default; its replies
held unread included) is refused more, in a reply to each, while the others are served.
The whole server's :data:`MAX_PENDING_REQUESTS` only protects the world's queue.
The requests of a client that disconnected are cancelled.
"""

from __future__ import annotations

import contextlib
import itertools
import queue
import time
from collections import Counter
from collections.abc import Callable
from concurrent.futures import Future, InvalidStateError
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from armfleet.errors import ArmfleetError
from armfleet.remote.client_quotas import how_to_raise
from armfleet.remote.outbox import Outbox
from armfleet.remote.wakeup import Wakeup
from armfleet.services.errors import ConnectionLost, RequestTimeout, TooManyRequests
from armfleet.services.protocol import MAX_IN_FLIGHT_PER_CLIENT, MAX_PENDING_REQUESTS, Service
from armfleet.services.run_state import RunState

if TYPE_CHECKING:
    from armfleet.world import World


@dataclass(eq=False)
class _Pending:
    peer: bytes
    request_id: int | None
    service: Service
    future: Future[Any]
    timeout_s: float
    #: Cancel the work if it has not started by then (monotonic) [s]; None: never.
    deadline: float | None
    #: Turns the work's result into the reply, in the server thread.
    finish: Callable[[Any], Any] | None = None
    #: Set when its client has gone: a wait stops polling.
    abandoned: bool = False


class PendingRequests:
    """Submits work to the world and answers each request once its future is done.

    Futures complete in the stepping thread; their callbacks only queue the
    request and wake the server thread, which replies.
    """

    def __init__(
        self,
        world: World,
        outbox: Outbox,
        wakeup: Wakeup,
        run_state: RunState | None,
        max_in_flight: int = MAX_IN_FLIGHT_PER_CLIENT,
    ) -> None:
        self._world = world
        self._max_in_flight = max_in_flight
        self._outbox = outbox
        self._wakeup = wakeup
        self._run_state = run_state
        self._pending: dict[int, _Pending] = {}
        self._per_peer: Counter[bytes] = Counter()
        self._completed: queue.SimpleQueue[int] = queue.SimpleQueue()
        self._keys = itertools.count()
        self._stopping = False

    def submit(
        self,
        peer: bytes,
        request_id: int | None,
        service: Service,
        work: Callable[[], Any],
        timeout: float,
        finish: Callable[[Any], Any] | None = None,
    ) -> None:
        """Run ``work`` at the next step boundary; cancel it if not started within ``timeout``.

        Raises:
            TooManyRequests: ``peer`` has too many requests in flight already.
        """
        self._check_room(peer)
        try:
            future = self._world.submit(work)
        except queue.Full:
            raise ArmfleetError("the world has too many requests waiting; try again") from None
        deadline = time.monotonic() + timeout
        self._track(_Pending(peer, request_id, service, future, timeout, deadline, finish))

    def wait(
        self,
        peer: bytes,
        request_id: int | None,
        check: Callable[[], Any],
        timeout: float,
        what: str,
    ) -> None:
        """Run ``check`` at every step boundary until it returns something (the reply).

        Raises:
            TooManyRequests: ``peer`` has too many requests in flight already.
        """
        self.repeat(peer, request_id, Service.WAIT, check, timeout=timeout, what=what)

    def repeat(
        self,
        peer: bytes,
        request_id: int | None,
        service: Service,
        work: Callable[[], Any],
        *,
        timeout: float | None = None,
        what: str = "",
        wake: bool = False,
    ) -> None:
        """Run ``work`` at step boundaries, again and again, until it returns something
        (the reply) or raises (the error reply). Each call goes to the back of the
        world's queue, so the requests that came meanwhile run between two calls.

        Args:
            timeout: reply ``RequestTimeout("<what> after <timeout> s")`` once this much
                wall time has passed [s]; None: no limit.
            wake: wake a paused loop for every call (work that makes progress by itself,
                as stepping), rather than calling it once per step or pause period.

        Raises:
            TooManyRequests: ``peer`` has too many requests in flight already.
        """
        self._check_room(peer)
        outcome: Future[Any] = Future()
        outcome.set_running_or_notify_cancel()
        deadline = None if timeout is None else time.monotonic() + timeout
        pending = _Pending(peer, request_id, service, outcome, timeout or 0.0, None)
        run_state = self._run_state if wake else None

        def settle(value: Any = None, error: BaseException | None = None) -> None:
            with contextlib.suppress(InvalidStateError):
                if error is not None:
                    outcome.set_exception(error)
                else:
                    outcome.set_result(value)

        def poll(previous: Future[Any] | None) -> None:
            if previous is not None:
                if previous.cancelled():
                    settle(error=ConnectionLost("the world is shutting down"))
                    return
                error = previous.exception()
                if error is not None or previous.result() is not None:
                    settle(None if error else previous.result(), error)
                    return
            if pending.abandoned:
                settle(error=ConnectionLost("the client went away"))
            elif deadline is not None and time.monotonic() > deadline:
                settle(error=RequestTimeout(f"{what} after {timeout:g} s"))
            elif self._stopping:
                settle(error=ConnectionLost("the world is shutting down"))
            else:
                try:
                    self._world.submit(work).add_done_callback(poll)
                except Exception as exc:
                    settle(error=exc)
                    return
                if run_state is not None:
                    run_state.wake()

        poll(None)
        self._track(pending)

    def in_flight(self, peer: bytes | None = None) -> int:
        """Requests not answered yet, of ``peer`` or of every client."""
        return len(self._pending) if peer is None else self._per_peer[peer]

    def _check_room(self, peer: bytes) -> None:
        if self._per_peer[peer] + self._outbox.held(peer) >= self._max_in_flight:
            raise TooManyRequests(self._max_in_flight, how_to_raise("requests_per_client"))
        if len(self._pending) >= MAX_PENDING_REQUESTS:
            raise ArmfleetError(
                f"the world has {len(self._pending)} requests in flight from "
                f"{len(self._per_peer)} clients; try again shortly"
            )

    def _track(self, pending: _Pending) -> None:
        key = next(self._keys)
        self._pending[key] = pending
        self._per_peer[pending.peer] += 1

        def done(_: Future[Any]) -> None:  # any thread: the stepping one, usually
            self._completed.put(key)
            self._wakeup.signal()

        pending.future.add_done_callback(done)
        if self._run_state is not None:
            self._run_state.wake()  # a loop sleeping between steps serves it at once

    def answer_completed(self) -> None:
        """Reply to every request whose work has finished."""
        while True:
            try:
                key = self._completed.get_nowait()
            except queue.Empty:
                return
            pending = self._pop(key)
            if pending is None:
                continue  # answered already (expired, or its client went away)
            try:
                if pending.future.cancelled():
                    raise ConnectionLost(f"{pending.service.value}: cancelled")
                result = pending.future.result()
                if pending.finish is not None:
                    result = pending.finish(result)
            except Exception as exc:
                if not pending.abandoned:
                    self._outbox.reply_error(pending.peer, pending.request_id, exc)
                continue
            if not pending.abandoned:
                self._outbox.reply(pending.peer, pending.request_id, result)

    def next_deadline(self) -> float | None:
        """The earliest deadline of work not yet answered (monotonic) [s], or None."""
        deadlines = [p.deadline for p in self._pending.values() if p.deadline is not None]
        return min(deadlines, default=None)

    def expire(self) -> None:
        """Cancel, with an error reply, work still queued past its deadline."""
        now = time.monotonic()
        for key, pending in tuple(self._pending.items()):
            if pending.deadline is not None and now > pending.deadline and pending.future.cancel():
                self._pop(key)
                error = RequestTimeout(
                    f"{pending.service.value}: the world did not take the request up within "
                    f"{pending.timeout_s:g} s (it is busy or not stepping); nothing was applied"
                )
                self._outbox.reply_error(pending.peer, pending.request_id, error)

    def cancel_client(self, peer: bytes) -> int:
        """Cancel the requests of ``peer``, which has gone (no reply: nobody would read it).

        Work not started yet never runs; waits stop polling at the next step. Work
        that ran already, or is running, with a ``finish`` (a subscription to register
        or undo) is finished when done, and answered to nobody.

        Returns:
            How many requests were cancelled.
        """
        if not self._per_peer[peer]:
            del self._per_peer[peer]
            return 0
        mine = [key for key, pending in self._pending.items() if pending.peer == peer]
        for key in mine:
            pending = self._pending[key]
            pending.abandoned = True
            # cancel() is False once the work runs (a wait runs from the start).
            if pending.future.cancel() or pending.finish is None:
                self._pop(key)
        return len(mine)

    def _pop(self, key: int) -> _Pending | None:
        pending = self._pending.pop(key, None)
        if pending is not None:
            self._per_peer[pending.peer] -= 1
            if not self._per_peer[pending.peer]:
                del self._per_peer[pending.peer]
        return pending

    def fail_all(self, reason: str) -> None:
        """Cancel what has not started and answer every request with ``reason``."""
        self._stopping = True
        for pending in self._pending.values():
            pending.future.cancel()
            self._outbox.reply_error(pending.peer, pending.request_id, ConnectionLost(reason))
        self._pending.clear()
        self._per_peer.clear()
