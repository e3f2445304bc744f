"""Would a new arm, at its start configuration, touch anything? Asked before it enters a world.

An arm that starts touching something stops its neighbour (a protective stop
mid-motion) and fails its own bring-up; so does an arm folded into itself or
into the floor by its initial positions. A distance between bases says little
about that: two Pandas at home touch with their bases 0.5 m apart, and a UR5
reaches further still. The real question is asked instead, of the physics
engine: the candidate body is loaded at its start configuration and its
closest points to everything else are read (``getClosestPoints``, which, unlike
contacts, needs no simulation step), with the contact monitor's rules of what
counts:

- itself: not links of one rigid piece or one joint apart, nor the pairs never
  seen touching (:func:`armfleet.physics.collision_filter.ignored_self_pairs`);
- the floor and static objects: not against the links that never move (the
  base standing on them);
- every other arm and every object: all links.

This runs before any controller or topic of the arm exists; on a failure the
body is removed again and the world is as it was. The world runs it in
:meth:`armfleet.World.spawn` (so the Python API, the CLI, launch and the live
API all ask it), and a launch spec check runs it in a scratch physics client
holding the spec's objects and arms at their start poses. A new scene object is
held to the same rule against the arms, whichever of the two comes first (see
:mod:`armfleet.objects.object_clearance`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import Enum

import pybullet as p

from armfleet.errors import StartPoseCollision
from armfleet.messages import FloatArray
from armfleet.physics.arm_body import ArmBody
from armfleet.physics.collision_filter import fixed_links, ignored_self_pairs, solid_links

#: Gap required between a new arm and anything else at its start pose [m]. Bring-up
#: moves a link by at most 0.025 mm (measured: 6 models, at home and at random
#: poses, link origins before and after bring-up); 1 mm is 40 times that.
CLEARANCE_M = 1e-3


class BodyKind(Enum):
    """What a body in the world is, for the clearance checks."""

    GROUND = "ground"
    ARM = "arm"
    STATIC_OBJECT = "static object"
    MOVING_OBJECT = "moving object"


@dataclass(frozen=True)
class Neighbour:
    """A body already in the world, as the clearance checks see it.

    Attributes:
        body_id: PyBullet body id.
        name: arm or object name, or ``"ground"``.
        links: link index -> link name (``{-1: ""}`` for an object or the ground).
        kind: ground, arm, static or moving object.
        fixed_links: its links that never move (an arm's base piece; ``{-1}`` for
            the ground and a static object; none for a moving object).
    """

    body_id: int
    name: str
    links: Mapping[int, str]
    kind: BodyKind
    fixed_links: frozenset[int] = frozenset()

    @property
    def supports(self) -> bool:
        """The ground or a static object: a new arm's links that never move may rest on it."""
        return self.kind in (BodyKind.GROUND, BodyKind.STATIC_OBJECT)


@dataclass(frozen=True)
class StartContact:
    """One link of the new arm too close to something.

    Attributes:
        link: the new arm's link.
        other: the arm, object or ``"ground"`` it is close to (the new arm's name: itself).
        other_link: the other link (``""`` for an object or the ground).
        distance_m: signed distance [m]; negative: they overlap.
    """

    link: str
    other: str
    other_link: str
    distance_m: float


def start_contacts(
    client: int,
    name: str,
    body: ArmBody,
    ignored_pairs: Iterable[tuple[str, str]],
    neighbours: Iterable[Neighbour],
    clearance_m: float = CLEARANCE_M,
) -> list[StartContact]:
    """Every link pair of the arm ``name`` (``body``, at its start configuration) closer
    than ``clearance_m`` to itself or a neighbour, deepest first."""
    names = {body.link_index(link): link for link in body.link_names}
    solid = set(solid_links(client, body))
    found: list[StartContact] = []
    ignored = ignored_self_pairs(client, body, ignored_pairs)
    for a, b, distance in closest_pairs(client, body.body_id, body.body_id, clearance_m):
        if a < b and a in solid and b in solid and (a, b) not in ignored:
            found.append(StartContact(names[a], name, names[b], distance))
    resting = fixed_links(body)
    for other in neighbours:
        if other.body_id == body.body_id:
            continue
        for a, b, distance in closest_pairs(client, body.body_id, other.body_id, clearance_m):
            if a in resting and other.supports:
                continue
            found.append(
                StartContact(names.get(a, ""), other.name, other.links.get(b, ""), distance)
            )
    return sorted(found, key=lambda contact: contact.distance_m)


def check_start_clearance(
    client: int,
    name: str,
    body: ArmBody,
    ignored_pairs: Iterable[tuple[str, str]],
    neighbours: Iterable[Neighbour],
) -> None:
    """Raise if the arm ``name`` (``body``) would touch anything at its start configuration.

    Raises:
        StartPoseCollision: naming the deepest contact: the arm's link, what it
            touches (arm and link, object, ``ground``, or itself) and the distance.
    """
    contacts = start_contacts(client, name, body, ignored_pairs, neighbours)
    if contacts:
        first = contacts[0]
        raise StartPoseCollision(
            name, first.link, first.other, first.other_link, first.distance_m, CLEARANCE_M
        )


def load_clear_body(
    client: int,
    name: str,
    urdf: str,
    joint_names: Sequence[str],
    start: FloatArray,
    ignored_pairs: Iterable[tuple[str, str]],
    neighbours: Iterable[Neighbour],
) -> ArmBody:
    """Load the arm's body at ``start`` (brakes on) if it touches nothing there.

    Raises:
        StartPoseCollision: it would touch something; the body is removed again.
        DescriptionError: PyBullet cannot load the URDF.
    """
    body = ArmBody(client, urdf, joint_names)
    try:
        body.reset(start)
        check_start_clearance(client, name, body, ignored_pairs, neighbours)
    except BaseException:
        body.remove()
        raise
    return body


def closest_pairs(
    client: int, first: int, second: int, distance_m: float
) -> list[tuple[int, int, float]]:
    """(link of ``first``, link of ``second``, signed distance [m]) of each pair closer
    than ``distance_m``."""
    points = p.getClosestPoints(first, second, distance_m, physicsClientId=client)
    return [(int(point[3]), int(point[4]), float(point[8])) for point in points or ()]
