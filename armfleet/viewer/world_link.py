"""The viewer attached to a world: what ``World(viewer=True)`` starts.

The world calls this listener's hooks (:class:`armfleet.world.WorldListener`); the
viewer itself knows no world, so a replay drives it the same way.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armfleet.viewer.viewer import Viewer, start_viewer
from armfleet.world.world_listener import WorldListener

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.objects import WorldObject
    from armfleet.world import World


class ViewerLink(WorldListener):
    """Shows ``world``'s arms and objects in ``viewer`` as they come, move and go."""

    def __init__(self, viewer: Viewer, world: World) -> None:
        self._viewer = viewer
        self._world = world

    def on_arm_ready(self, arm: Arm) -> None:
        self._viewer.add_arm(arm)

    def on_arm_removed(self, name: str) -> None:
        self._viewer.remove_arm(name)

    def on_object_added(self, obj: WorldObject) -> None:
        self._viewer.add_object(obj)

    def on_object_removed(self, name: str) -> None:
        self._viewer.remove_object(name)

    def on_step(self) -> None:
        self._viewer.tick(self._world)

    def on_close(self) -> None:
        self._viewer.close()


def start_world_viewer(world: World, port: int | None = None) -> tuple[Viewer | None, str | None]:
    """Start a viewer showing ``world`` from now on; ``(None, reason)`` if it cannot start.

    The ``viewer`` front end of the ``armfleet.front_ends`` entry points.
    """
    viewer, reason = start_viewer(port)
    if viewer is not None:
        for arm in world.arms.values():
            viewer.add_arm(arm)
        for obj in world.objects.values():
            viewer.add_object(obj)
        world.attach(ViewerLink(viewer, world))
    return viewer, reason
