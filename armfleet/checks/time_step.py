"""The physics step a world may run at: one rule for :class:`armfleet.World` and launch specs.

Bounds, found by experiment (issue #14, item 4: each model brought up alone, then
moved +0.3 rad per joint and left 0.2 s to settle, measured 2026-11-23):

- below ``MIN_DT_S`` a second of simulation costs more than 100,000 steps (at
  ``1e-9`` s, 1 ms took 35 s): a typo, not a choice;
- above ``MAX_DT_S`` a shipped model no longer meets the tracking figures of
  issue #2 (max |q_ref - q| < 1e-3 rad during a move, < 1e-4 rad once settled):
  from 2.2 ms a Panda's wrist no longer settles (joints 5-6 keep oscillating by
  2e-4 to 4e-4 rad, its fingers drift; 4 ms happens to pass), from 4.6 ms it does
  not bring up at all; UR3/5/10, xArm7 and Z1 track up to 10 ms.

Measured with ``python benchmarks/dt_limits.py``.
"""

from __future__ import annotations

from armfleet.checks.real_numbers import real_number

#: Smallest physics step [s].
MIN_DT_S = 1e-5
#: Largest physics step [s] at which every shipped model brings up and tracks.
MAX_DT_S = 0.002
#: What a valid step is, for messages.
DT_VALID = (
    f"a step in [{MIN_DT_S:g}, {MAX_DT_S:g}] s (above {MAX_DT_S:g} s a Panda's wrist "
    "no longer settles on its target)"
)


def check_dt(dt: object) -> float:
    """``dt`` [s] as a float if it is a number within [``MIN_DT_S``, ``MAX_DT_S``].

    Raises:
        InvalidNumber: naming dt and the valid range.
    """
    return real_number(dt, "dt", DT_VALID, low=MIN_DT_S, high=MAX_DT_S)
