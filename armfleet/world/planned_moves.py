"""Planned moves asked by other threads (the live API, Foxglove), planned off the stepping
thread so that the world goes on stepping and serving everyone meanwhile.

A move goes in three parts:

1. on the stepping thread, inside the request: the planner reads the world
   (:meth:`~armfleet.planning.motion_planner.MotionPlanner.prepare`; cheap). A bad
   request (unknown arm, moving arm, bad target) is refused here, at once;
2. on one of :data:`PLANNING_THREADS` worker threads: the plan is made from what was read
   alone (:meth:`~armfleet.planning.motion_planner.MotionPlanner.solve`: IK, search,
   proof, timing, the check in time against the arms that were moving); more requests
   wait their turn. The world steps and answers every other request meanwhile;
3. back on the stepping thread, at a step boundary: the plan is executed, which checks it
   again against the world as it is then (its arms still at rest where it starts, still
   clear of everything, still clear in time of the arms that move). A plan that no
   longer holds (:class:`~armfleet.planning.motion_planner.StalePlan`: e.g. another
   client moved its arm meanwhile) is planned again once, from where the arms are then,
   within what is left of its time budget (the time its first plan took, not the time
   it waited for a thread, is spent); failing that it is refused in one line.

The request's reply comes when the motion starts (or the plan fails), as for a move
planned on the stepping thread. The in-process Python API (``arm.move_to(...,
avoid_collisions=True)``) plans on the caller's thread, which is the one stepping the
world: it returns once the motion has started, as before.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping
from concurrent.futures import Future, InvalidStateError
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from armfleet.errors import ArmfleetError
from armfleet.motion.move_options import PlanningLimit
from armfleet.planning import MotionPlanner, Plan
from armfleet.planning.motion_planner import StalePlan
from armfleet.runtime.request_queue import Deferred
from armfleet.runtime.worker_threads import WorkerThreads

T = TypeVar("T")

#: Plans made at once; more wait their turn. Python runs one thread at a time, so more
#: threads would not plan faster: two let a short plan pass a long one.
PLANNING_THREADS = 2
#: Plans a move may be given when the world changed under it: the first, and one again.
ATTEMPTS = 2
#: Least time budget left worth planning again with [s].
MIN_REPLAN_S = 0.05


@dataclass
class _Move(Generic[T]):
    """One planned move on its way: what was asked, and where its answer goes."""

    goals: Mapping[str, Any]
    options: dict[str, Any]
    reply: Callable[[float], T]
    answer: Deferred[T]
    attempts: int = 0
    #: Wall time its plans took so far (not the time they waited for a thread) [s].
    spent_s: float = 0.0
    #: The first request's time or iteration budget (None until it is read).
    limit: PlanningLimit | None = None


class PlannedMoves:
    """Planned moves of one world, planned on worker threads.

    Args:
        planner: the world's planner.
        submit: hands a function to the stepping thread (``world.submit``).
    """

    def __init__(
        self, planner: MotionPlanner, submit: Callable[[Callable[[], Any]], Future[Any]]
    ) -> None:
        self._planner = planner
        self._submit = submit
        self._workers = WorkerThreads("armfleet-planning", PLANNING_THREADS)

    def start(
        self, goals: Mapping[str, Any], options: Mapping[str, Any], reply: Callable[[float], T]
    ) -> Deferred[T]:
        """Plan ``goals`` with the plan's ``options`` (``clearance_m``, ``timeout_s``...) on a
        worker thread, then start the motion on the stepping thread; call it on the
        stepping thread (a request's work).

        Returns:
            The answer, once the motion has started: ``reply(duration)``, called on the
            stepping thread right after the start; or the planning failure.

        Raises:
            ArmfleetError: the request is refused as it is read (unknown arm, an arm moving,
                a bad target or option): at once, nothing planned.
        """
        move = _Move(goals, dict(options), reply, Deferred())
        move.answer.set_running_or_notify_cancel()
        self._attempt(move)
        return move.answer

    def close(self) -> None:
        """Plan nothing more; requests waiting for a thread fail (the world is closing)."""
        self._workers.close()

    def _attempt(self, move: _Move[T]) -> None:
        """Read the world for ``move`` and hand the plan to a worker (stepping thread)."""
        move.attempts += 1
        request = self._planner.prepare(move.goals, **move.options)
        move.limit = move.limit or request.limit
        planned = self._workers.submit(lambda: self._planner.solve(request, sampled=True))
        planned.add_done_callback(lambda done: self._hand_back(move, done))

    def _hand_back(self, move: _Move[T], planned: Future[Plan]) -> None:
        """Give a finished plan to the stepping thread (a worker thread)."""
        try:
            started = self._submit(lambda: self._finish(move, planned))
        except Exception as exc:  # the world closed, or its queue is full
            _fail(move.answer, exc)
            return
        started.add_done_callback(lambda done: _fail_if_failed(move.answer, done))

    def _finish(self, move: _Move[T], planned: Future[Plan]) -> None:
        """Start a finished plan, or plan it again if it no longer holds (stepping thread)."""
        try:
            plan = planned.result()
            move.spent_s += plan.planning_time_s
            duration = self._planner.execute(plan)
            result = move.reply(duration)
        except StalePlan as exc:
            self._again(move, exc)
        except Exception as exc:
            _fail(move.answer, exc)
        except BaseException as exc:  # Ctrl-C: tell the client, then stop
            _fail(move.answer, exc)
            raise
        else:
            with contextlib.suppress(InvalidStateError):
                move.answer.set_result(result)

    def _again(self, move: _Move[T], stale: StalePlan) -> None:
        """Plan ``move`` again from where its arms are now, or refuse it in one line."""
        limit = move.limit
        assert limit is not None  # set by the first attempt
        options = dict(move.options)
        left = float("inf")  # an iteration budget is given again in full
        if limit.budget is None:
            left = limit.timeout_s - move.spent_s
            options["timeout_s"] = left
        if move.attempts >= ATTEMPTS:
            _fail(move.answer, StalePlan(f"{stale} (planned {move.attempts} times)"))
            return
        if left < MIN_REPLAN_S:
            _fail(move.answer, StalePlan(f"{stale} (its time budget is spent)"))
            return
        move.options = options
        try:
            self._attempt(move)
        except Exception as exc:
            _fail(move.answer, exc)


def _fail(answer: Future[Any], error: BaseException) -> None:
    with contextlib.suppress(InvalidStateError):
        answer.set_exception(error)


def _fail_if_failed(answer: Future[Any], started: Future[Any]) -> None:
    """The hand-back never ran (the world closed first): fail the answer with why."""
    if started.cancelled():
        _fail(answer, ArmfleetError("the world closed before the plan could start"))
    elif started.exception() is not None:
        _fail(answer, started.exception() or ArmfleetError("the plan could not start"))
