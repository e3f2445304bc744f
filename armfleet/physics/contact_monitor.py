"""Every step, the world's contacts that matter: between arms, an arm and itself, the floor,
and scene objects (body name = object name, link ``""``).

Contacts ruled out at spawn (see :mod:`armfleet.physics.collision_filter`) never appear;
nor do those between a static object and an arm's links that never move (an
arm standing on a table).
A report goes out on ``/collisions`` at each step with contacts, plus an empty
one when they end. A contact between links that were not touching at the
previous step, or one that has gone 2 mm deeper since first seen, is handed to
``on_new_contact``.
"""

from __future__ import annotations

from collections.abc import Callable

import pybullet as p

from armfleet import topics
from armfleet.messages import CollisionReport, Contact
from armfleet.physics.arm_body import ArmBody
from armfleet.physics.collision_filter import fixed_links, rigid_groups
from armfleet.physics.start_clearance import BodyKind, Neighbour
from armfleet.runtime.bus import Bus

GROUND = "ground"
#: PyBullet reports points within its contact margin; closer than this counts as touching [m].
TOUCH_DISTANCE_M = 0.0
#: A touching pair that goes this much deeper counts as a new contact [m].
DEEPER_M = 0.002


class ContactMonitor:
    """Reads contacts after each physics step and reports them.

    Args:
        client: PyBullet client id.
        ground: body id of the floor.
        bus: where reports are published.
        on_new_contact: called as ``(contact, deeper)`` for each contact whose link
            pair was not touching at the previous step (``deeper`` False), or has gone
            :data:`DEEPER_M` deeper than when first seen (``deeper`` True).
    """

    def __init__(
        self, client: int, ground: int, bus: Bus, on_new_contact: Callable[[Contact, bool], None]
    ) -> None:
        self._client = client
        self._ground = ground
        self._bodies: dict[int, tuple[str, dict[int, str]]] = {ground: (GROUND, {-1: ""})}
        self._bus = bus
        self._on_new_contact = on_new_contact
        self._touching: dict[tuple[str, str], float] = {}
        self._touching_bodies: dict[str, set[str]] = {}
        self._arms: dict[int, ArmBody] = {}
        self._static_objects: set[int] = set()
        self._dynamic_objects: dict[int, str] = {}
        self.total_contacts = 0
        bus.advertise(topics.COLLISIONS, CollisionReport)

    def add_arm(self, name: str, body: ArmBody) -> None:
        links = {index: link for link, index in ((n, body.link_index(n)) for n in body.link_names)}
        self._bodies[body.body_id] = (name, links)
        self._arms[body.body_id] = body
        for static in self._static_objects:
            self._ignore_fixed_links(static, body)

    def remove_arm(self, body: ArmBody) -> None:
        self._bodies.pop(body.body_id, None)
        self._arms.pop(body.body_id, None)

    def add_object(self, name: str, body_id: int, *, static: bool) -> None:
        """Report contacts of the scene object ``name`` (one PyBullet body, no links)."""
        self._bodies[body_id] = (name, {-1: ""})
        if static:
            self._static_objects.add(body_id)
            for arm in self._arms.values():
                self._ignore_fixed_links(body_id, arm)
        else:
            self._dynamic_objects[body_id] = name

    def remove_object(self, body_id: int) -> None:
        self._bodies.pop(body_id, None)
        self._static_objects.discard(body_id)
        self._dynamic_objects.pop(body_id, None)

    def neighbours(self) -> tuple[Neighbour, ...]:
        """Every body watched here (floor, arms, objects), for a newcomer's clearance check."""
        return tuple(
            Neighbour(body_id, name, dict(links), *self._kind(body_id))
            for body_id, (name, links) in self._bodies.items()
        )

    def _kind(self, body_id: int) -> tuple[BodyKind, frozenset[int]]:
        """What the body is, and its links that never move."""
        if body_id in self._arms:
            return BodyKind.ARM, frozenset(fixed_links(self._arms[body_id]))
        if body_id in self._dynamic_objects:
            return BodyKind.MOVING_OBJECT, frozenset()
        kind = BodyKind.GROUND if body_id == self._ground else BodyKind.STATIC_OBJECT
        return kind, frozenset({-1})

    def is_dynamic_object(self, name: str) -> bool:
        """Whether ``name`` is a scene object with a mass (arms may touch it freely)."""
        return name in self._dynamic_objects.values()

    def _ignore_fixed_links(self, static: int, arm: ArmBody) -> None:
        """A static object and an arm's links that never move: nothing to report or solve."""
        for link, group in rigid_groups(arm).items():
            if group == -1:
                p.setCollisionFilterPair(
                    static, arm.body_id, -1, link, 0, physicsClientId=self._client
                )

    @property
    def touching(self) -> dict[tuple[str, str], float]:
        """Link pairs touching at the last step, with their first-seen depth [m]."""
        return dict(self._touching)

    def touching_bodies(self, name: str) -> set[str]:
        """Bodies (arm and object names, ``"ground"``) that ``name`` touched at the last step."""
        return set(self._touching_bodies.get(name, ()))

    def scan(self, stamp: float) -> tuple[Contact, ...]:
        """Read, report and return the contacts of the last step."""
        contacts = []
        for point in p.getContactPoints(physicsClientId=self._client):
            distance = point[8]
            if distance > TOUCH_DISTANCE_M:
                continue
            a, b = self._bodies.get(point[1]), self._bodies.get(point[2])
            if a is None or b is None:
                continue
            contacts.append(
                Contact(
                    a[0],
                    a[1].get(point[3], ""),
                    b[0],
                    b[1].get(point[4], ""),
                    tuple(point[5]),
                    tuple(point[7]),
                    -distance,
                )
            )
        if contacts or self._touching:
            self._publish_and_track(stamp, contacts)
        return tuple(contacts)

    def _publish_and_track(self, stamp: float, contacts: list[Contact]) -> None:
        self.total_contacts += len(contacts)
        self._bus.publish(topics.COLLISIONS, CollisionReport(stamp, tuple(contacts)))
        deepest: dict[tuple[str, str], Contact] = {}
        for contact in contacts:
            if contact.pair not in deepest or contact.depth > deepest[contact.pair].depth:
                deepest[contact.pair] = contact
        self._touching_bodies = {}
        for contact in contacts:
            self._touching_bodies.setdefault(contact.body_a, set()).add(contact.body_b)
            self._touching_bodies.setdefault(contact.body_b, set()).add(contact.body_a)
        previous, self._touching = self._touching, {}
        for pair, contact in deepest.items():
            first_depth = previous.get(pair)
            deeper = first_depth is not None and contact.depth > first_depth + DEEPER_M
            if first_depth is None or deeper:
                self._on_new_contact(contact, deeper)
                first_depth = contact.depth
            self._touching[pair] = first_depth
