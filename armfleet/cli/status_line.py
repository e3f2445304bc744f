"""The compact state line ``armfleet spawn`` shows while the world runs."""

from __future__ import annotations

from armfleet.world import World


def status_line(world: World, realtime_factor: float) -> str:
    """E.g. ``t=12.0s rtf=1.00 | bob holding q=[+0.00 -0.79 ...] | toby moving q=[...]``."""
    parts = [f"t={world.time:.1f}s rtf={realtime_factor:.2f}"]
    for name, arm in world.arms.items():
        state = "moving" if arm.is_moving else "holding"
        q = " ".join(f"{v:+.2f}" for v in arm.positions)
        parts.append(f"{name} {state} q=[{q}]")
    return " | ".join(parts)
