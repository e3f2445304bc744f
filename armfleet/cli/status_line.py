"""The compact state line ``armfleet spawn`` shows while the world runs.

One part per arm while that fits the terminal; beyond its width (many arms), a
summary: how many arms are in each mode, and the arms that need attention.
"""

from __future__ import annotations

import shutil
from collections import Counter
from typing import TYPE_CHECKING

from armfleet.messages import ArmMode, ArmStatus

if TYPE_CHECKING:  # types only; the simulator loads when a world starts
    from armfleet.world import World

#: Width assumed when the output is not a terminal (a pipe, a log file) [characters].
NON_TTY_WIDTH = 100
#: Modes of an arm that needs attention, and how the line shows them.
ATTENTION = {ArmMode.PROTECTIVE_STOP: "STOP", ArmMode.ERROR: "ERROR"}


def terminal_width() -> int:
    """Columns of the terminal (``$COLUMNS`` if set), :data:`NON_TTY_WIDTH` if none."""
    return shutil.get_terminal_size((NON_TTY_WIDTH, 24)).columns


def status_line(world: World, realtime_factor: float, width: int | None = None) -> str:
    """E.g. ``t=12.0s rtf=1.00 touching=0 | bob holding q=[+0.00 -0.79 ...] | toby moving ...``.

    A stopped arm shows ``STOP(<reason>)``, a faulted one ``ERROR(<reason>)``, and
    ``sat=N`` counts its control updates that hit an effort limit. When that line is
    wider than ``width`` (default: the terminal's), :func:`summary_line` instead.
    """
    touching = sum(len(world.contacts.touching_bodies(name)) for name in world.arms) // 2
    head = f"t={world.time:.1f}s rtf={realtime_factor:.2f} touching={touching}"
    statuses = {name: arm.status(world.time) for name, arm in world.arms.items()}
    parts = [head]
    for name, arm in world.arms.items():
        status = statuses[name]
        saturated = sum(status.saturation_steps)
        q = " ".join(f"{v:+.2f}" for v in arm.positions)
        parts.append(
            f"{name} {_state(status)} q=[{q}]" + (f" sat={saturated}" if saturated else "")
        )
    line = " | ".join(parts)
    width = terminal_width() if width is None else width
    return line if len(line) <= width else summary_line(head, statuses, width)


def summary_line(head: str, statuses: dict[str, ArmStatus], width: int) -> str:
    """E.g. ``t=3.0s rtf=1.00 touching=2 | 30 arms: 27 holding, 1 moving, 2 protective stop
    | attention: carl STOP(contact with dave), dave STOP(contact with carl)``.

    Modes are counted in :class:`ArmMode` order; the arms needing attention (stopped
    or faulted) are listed while they fit in ``width``, then ``+N more`` (``N arms``
    if none fits).
    """
    counts = Counter(status.mode for status in statuses.values())
    modes = ", ".join(f"{counts[mode]} {mode.value}" for mode in ArmMode if counts[mode])
    line = f"{head} | {len(statuses)} arms: {modes or 'none'}"
    attention = [
        f"{name} {_state(status)}" for name, status in statuses.items() if status.mode in ATTENTION
    ]
    if not attention:
        return line
    line += " | attention: "
    shown: list[str] = []
    for index, part in enumerate(attention):
        rest = len(attention) - index - 1
        candidate = ", ".join([*shown, part]) + (f", +{rest} more" if rest else "")
        if len(line) + len(candidate) > width:
            break
        shown.append(part)
    hidden = len(attention) - len(shown)
    if not shown:
        return f"{line}{hidden} arms"
    return line + ", ".join([*shown, f"+{hidden} more"] if hidden else shown)


def _state(status: ArmStatus) -> str:
    """``holding``, ``moving``, ``STOP(<reason>)`` or ``ERROR(<reason>)``."""
    label = ATTENTION.get(status.mode)
    return status.mode.value if label is None else f"{label}({status.reason})"
