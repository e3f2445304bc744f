"""The compact state line ``armfleet spawn`` shows while the world runs."""

from __future__ import annotations

from armfleet.messages import ArmMode
from armfleet.world import World


def status_line(world: World, realtime_factor: float) -> str:
    """E.g. ``t=12.0s rtf=1.00 contacts=0 | bob holding q=[+0.00 -0.79 ...] | toby moving ...``.

    A stopped arm shows ``STOP(<reason>)``, a faulted one ``ERROR(<reason>)``, and
    ``sat=N`` counts its control updates that hit an effort limit.
    """
    touching = sum(len(world.contacts.touching_bodies(name)) for name in world.arms) // 2
    parts = [f"t={world.time:.1f}s rtf={realtime_factor:.2f} touching={touching}"]
    for name, arm in world.arms.items():
        status = arm.status(world.time)
        state = status.mode.value
        if status.mode in (ArmMode.PROTECTIVE_STOP, ArmMode.ERROR):
            state = (
                f"{'STOP' if status.mode is ArmMode.PROTECTIVE_STOP else 'ERROR'}({status.reason})"
            )
        saturated = sum(status.saturation_steps)
        q = " ".join(f"{v:+.2f}" for v in arm.positions)
        parts.append(f"{name} {state} q=[{q}]" + (f" sat={saturated}" if saturated else ""))
    return " | ".join(parts)
