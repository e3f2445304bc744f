"""What a front end hears from the world it watches: the listener interface.

The viewer, the recorders and the Foxglove server sit above the world and attach to it
(:meth:`armfleet.World.attach`); the world calls their hooks and names none of them.
Every hook is a no-op here, so a listener overrides only what it needs (as
foxglove-sdk's ``ServerListener``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.objects import WorldObject


class WorldListener:
    """Hooks the world calls from its stepping thread, between two steps or at a step's end.

    A hook that raises is logged and the listener is detached: a front end never stops
    the world.
    """

    def on_arm_ready(self, arm: Arm) -> None:
        """``arm`` finished its bring-up and holds its pose."""

    def on_arm_removed(self, name: str) -> None:
        """The arm ``name`` is leaving the world (its handles still work during the call)."""

    def on_object_added(self, obj: WorldObject) -> None:
        """``obj`` was added to the scene."""

    def on_object_removed(self, name: str) -> None:
        """The object ``name`` is leaving the scene (still there during the call)."""

    def on_step(self) -> None:
        """A step ended: the state describes the new time."""

    def on_close(self) -> None:
        """The world is closing: release what the listener holds (handles still work)."""
