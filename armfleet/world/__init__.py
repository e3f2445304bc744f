"""The world: one PyBullet world, its arms and objects, stepped by one thread.

Owns :class:`World`, the bring-up of one arm at a time (:mod:`~armfleet.world.bringup`),
:func:`~armfleet.world.launch.launch` (a spec to a running world), the listener interface
front ends attach with (:class:`WorldListener`) and the registry they are found in
(:mod:`~armfleet.world.front_ends`).

Rule: imports every core room below it (spec, arms, safety, planning, ...); never a front
end (viewer, recording, Foxglove, the live API, sweeps, environments): they attach.
"""

from armfleet.world.world import World
from armfleet.world.world_listener import WorldListener

__all__ = ["World", "WorldListener"]
