"""Protective stops: arms that touch something stop, hold, and wait for a reset.

After ``reset_stop()`` an arm may move away from what it is touching: contacts
with those bodies don't stop it again until they have separated once (unless
it pushes 2 mm deeper). Any other new contact stops it again.

Scene objects with a mass are what arms are for: touching, pushing or holding
one never stops an arm. A static object (a table) is an obstacle like the
floor. Contacts between objects, or with the floor, concern no arm.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Protocol

from armfleet.controllers import PositionController
from armfleet.messages import Contact
from armfleet.physics.contact_monitor import ContactMonitor


class Stoppable(Protocol):
    """An arm as the supervisor stops and releases it."""

    @property
    def name(self) -> str: ...
    @property
    def position_controller(self) -> PositionController: ...


class SafetySupervisor:
    """Decides which contacts stop which arms.

    Args:
        monitor: the world's contact monitor.
        arms: callable returning the world's arms by name.
        on_stop: called with an arm that has just gone to protective stop.
    """

    def __init__(
        self,
        monitor: ContactMonitor,
        arms: Callable[[], Mapping[str, Stoppable]],
        on_stop: Callable[[Stoppable], None],
    ) -> None:
        self._monitor = monitor
        self._arms = arms
        self._on_stop = on_stop
        self._excused: dict[str, set[str]] = {}
        self.stops = 0

    def on_new_contact(self, contact: Contact, deeper: bool) -> None:
        arms = self._arms()
        for name, other in ((contact.body_a, contact.body_b), (contact.body_b, contact.body_a)):
            arm = arms.get(name)
            if arm is None or (other in self._excused.get(name, ()) and not deeper):
                continue
            if self._monitor.is_dynamic_object(other):
                continue
            touched = "itself" if other == name else other
            links = f"{contact.link_a or contact.body_a} / {contact.link_b or contact.body_b}"
            if arm.position_controller.protective_stop(f"touched {touched} ({links})"):
                self.stops += 1
                self._on_stop(arm)
            if contact.body_a == contact.body_b:
                break  # a self-contact concerns one arm once

    def after_scan(self) -> None:
        """Excuses end once the bodies have separated."""
        for name in list(self._excused):
            self._excused[name] &= self._monitor.touching_bodies(name)
            if not self._excused[name]:
                del self._excused[name]

    def reset_stop(self, arm: Stoppable) -> None:
        """Let ``arm`` move again, free to leave the bodies it touches now."""
        touching = self._monitor.touching_bodies(arm.name)
        if touching:
            self._excused[arm.name] = touching
        arm.position_controller.reset_stop()
