"""``step N`` over the live API, in slices that let the other clients' requests through.

The world serves requests between two steps, one request at a time, so one request
that stepped a paused world 100,000 times held every other client's requests until it
was done: 28 s measured with a few Pandas. Here a step request steps for at most
:data:`STEP_SLICE_S` of wall time, then goes to the back of the world's queue: the
requests that came meanwhile (another client's ``info``, ``move``, ``wait`` check)
run, then the next slice. The steps themselves are the same as one long loop: only
what other clients ask runs between them, as it would between two ``step`` requests.

The request stops early, with an error saying how far it got, if another client
resumes the world meanwhile (the world then runs on by itself), and at once if its
own client goes away.
"""

from __future__ import annotations

import time
from typing import Any

from armfleet.checks.number_ranges import STEP_COUNT
from armfleet.errors import ArmfleetError
from armfleet.services.arguments import Arguments
from armfleet.services.errors import RequestTimeout
from armfleet.services.run_state import RunState
from armfleet.world import World

#: Wall time one slice of a step request may step the world before the requests that
#: came meanwhile get their turn [s]: what another client waits at most for a step.
STEP_SLICE_S = 0.02


class StepInterrupted(ArmfleetError):
    """Another client resumed the world during a ``step`` request, which stopped there.

    Attributes:
        done: steps made of ``count``.
        count: steps asked for.
    """

    def __init__(self, done: int, count: int, time_s: float) -> None:
        self.done, self.count = done, count
        super().__init__(
            f"step: another client resumed the world after {done} of {count} steps "
            f"(t={time_s:.3f} s); it runs on by itself now: pause it again to step"
        )


class SlicedSteps:
    """The work of one ``step`` request: called at step boundaries until it returns the
    reply (None until then).

    Args:
        world: the world, stepped in its own thread (where this is called).
        run_state: its loop's run control; the world must stay paused throughout.
        count: steps to make.
        slice_s: wall time of stepping per call [s] (at least one step is made).
        start_within_s: refuse, unapplied, if the first slice starts later than this [s]
            (the request's own timeout: its client has given up by then).
    """

    def __init__(
        self,
        world: World,
        run_state: RunState,
        count: int,
        slice_s: float = STEP_SLICE_S,
        start_within_s: float | None = None,
    ) -> None:
        self._world = world
        self._run_state = run_state
        self.count = count
        self._slice_s = slice_s
        self._start_within_s = start_within_s
        self._start_by = None if start_within_s is None else time.monotonic() + start_within_s
        #: Steps made so far.
        self.done = 0

    @classmethod
    def from_request(
        cls, world: World, run_state: RunState | None, args: Arguments, timeout: float
    ) -> SlicedSteps:
        """Check a ``step`` request (in the server thread, before the world is touched);
        ``timeout``: the request's wait to be taken up [s].

        Raises:
            ProtocolError: ``count`` is not an integer in 1..100000.
            ArmfleetError: the world is stepped by its own program (no run loop to pause).
        """
        count = args.in_range("count", 1, STEP_COUNT)
        if run_state is None:
            raise ArmfleetError("step: this world is stepped by its own program, not paused")
        return cls(world, run_state, count, start_within_s=timeout)

    def __call__(self) -> dict[str, Any] | None:
        """Step one slice; the reply once every step is made.

        Raises:
            RequestTimeout: the world took the request up too late (nothing was applied).
            ArmfleetError: the world runs (not paused) when the request starts.
            StepInterrupted: another client resumed it between two slices.
        """
        world = self._world
        if self.done == 0 and self._start_by is not None and time.monotonic() > self._start_by:
            raise RequestTimeout(
                f"step: the world did not take the request up within "
                f"{self._start_within_s:g} s (it is busy or not stepping); nothing was applied"
            )
        if not self._run_state.paused:
            if self.done == 0:
                raise ArmfleetError("step: the world is running; pause it first")
            raise StepInterrupted(self.done, self.count, world.time)
        ends = time.perf_counter() + self._slice_s
        while self.done < self.count:
            world.step()
            self.done += 1
            if time.perf_counter() >= ends:
                break
        self._run_state.note_progress(world.time)
        if self.done < self.count:
            return None
        return {"time_s": world.time, "paused": True}
