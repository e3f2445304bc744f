"""The world: one PyBullet world, its arms and objects, stepped by one thread.

Owns :class:`World`, the bring-up of one arm at a time (:mod:`~armfleet.world.bringup`),
:func:`~armfleet.world.launch.launch` (a spec to a running world), the listener interface
front ends attach with (:class:`WorldListener`), the registry they are found in
(:mod:`~armfleet.world.front_ends`), and the planned moves front ends ask for, planned
off the stepping thread (:mod:`~armfleet.world.planned_moves`).

Rule: imports every core room below it (spec, arms, safety, planning, ...); never a front
end (viewer, recording, Foxglove, the live API, sweeps, environments): they attach.
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.world.world import World
    from armfleet.world.world_listener import WorldListener

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "World": "armfleet.world.world",
        "WorldListener": "armfleet.world.world_listener",
    },
)

__all__ = ["World", "WorldListener"]
