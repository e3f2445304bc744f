"""The loop that steps a world run from the command line: pacing, pause, status.

Requests from the live API are served at step boundaries: by ``world.step()``
itself, while the loop waits for the wall clock (so a request does not wait for
the next step), and while paused (the world does not step then).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # types only; the simulator loads when a world starts
    from armfleet.remote import RunState
    from armfleet.world import World


STATUS_PERIOD_S = 1.0
#: Falling further behind the wall clock than this (a long bring-up) is not caught up [s].
MAX_LAG_S = 0.25
#: Period of progress reports to the run state (for its real-time factor) [s].
PROGRESS_PERIOD_S = 0.05
#: Longest sleep while paused: requests wake the loop sooner [s].
PAUSED_SLEEP_S = 0.1


def run_world(
    world: World,
    run_state: RunState,
    duration: float | None,
    realtime: bool,
    on_status: Callable[[float], None],
    on_pause: Callable[[bool], None],
) -> None:
    """Step ``world`` for ``duration`` simulated seconds (None: until interrupted).

    Args:
        run_state: pause flag and wake-ups shared with the API server.
        realtime: pace the simulation to the wall clock.
        on_status: called about once a second with the real-time factor.
        on_pause: called with True when a pause takes effect, False on resume.
    """
    origin = world.time
    anchor_sim, anchor_wall = world.time, time.monotonic()
    next_status = anchor_wall + STATUS_PERIOD_S
    next_progress = anchor_wall
    paused = False
    while duration is None or world.time - origin < duration - 1e-9:
        # Serve requests here rather than inside step(), so a pause stops the world
        # at exactly this boundary.
        world.process_requests()
        if run_state.paused:
            if not paused:
                paused = True
                on_pause(True)
            run_state.sleep(PAUSED_SLEEP_S)
            continue
        if paused:
            paused = False
            on_pause(False)
            anchor_sim, anchor_wall = world.time, time.monotonic()
        world.step()
        now = time.monotonic()
        if realtime:
            ahead = (world.time - anchor_sim) - (now - anchor_wall)
            if ahead < -MAX_LAG_S:
                anchor_sim, anchor_wall = world.time, now  # do not sprint to catch up
            while ahead > 0 and not run_state.paused:
                run_state.sleep(ahead)
                world.process_requests()
                now = time.monotonic()
                ahead = (world.time - anchor_sim) - (now - anchor_wall)
        if now >= next_progress:
            run_state.note_progress(world.time, now)
            next_progress = now + PROGRESS_PERIOD_S
        if now >= next_status:
            on_status(run_state.realtime_factor or 0.0)
            next_status = now + STATUS_PERIOD_S
