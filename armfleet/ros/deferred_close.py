"""Taking an action server down without cutting off the goals it is ending.

When an arm leaves, its goals end at once (aborted, with the reason), but each one's
result still has to go out from its executor thread. Destroying the server right away
would lose those results: the server is destroyed once its goals have returned, in a
thread of its own, so the stepping thread never waits for it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

#: Longest wait for the goals to return [s of wall time].
GOALS_WAIT_S = 5.0
#: Time left for the last results to be sent after the goals returned [s].
RESULTS_GRACE_S = 0.5


class GoalCount:
    """How many goals of one server are executing (their executor threads)."""

    def __init__(self) -> None:
        self._count = 0
        self._idle = threading.Condition()

    def __enter__(self) -> GoalCount:
        with self._idle:
            self._count += 1
        return self

    def __exit__(self, *exc: object) -> None:
        with self._idle:
            self._count -= 1
            self._idle.notify_all()

    def wait_idle(self, timeout: float) -> bool:
        with self._idle:
            return self._idle.wait_for(lambda: self._count == 0, timeout)


def close_when_idle(goals: GoalCount, destroy: Callable[[], None]) -> threading.Thread:
    """Call ``destroy`` once ``goals`` are done (at most :data:`GOALS_WAIT_S`) and their
    results had :data:`RESULTS_GRACE_S` to go out; returns at once, with the thread that
    does it (join it before destroying the node the server belongs to)."""

    def wait_then_destroy() -> None:
        goals.wait_idle(GOALS_WAIT_S)
        time.sleep(RESULTS_GRACE_S)
        destroy()

    thread = threading.Thread(target=wait_then_destroy, name="armfleet-ros-retire", daemon=True)
    thread.start()
    return thread
