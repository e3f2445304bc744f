"""Would a new scene object touch anything where it is added? Asked before it enters a world.

An object added inside an arm's links is pushed out by the physics solver with
whatever force it takes. Measured on a Panda holding at home: a static 10 cm box
added around its hand stopped it (protective stop), then its joints moved by up
to 2.8 rad; a 0.5 kg box there did not stop it (arms may touch moving objects),
but its joints moved by up to 1.3 rad and the box flew 3 m up. Such an object is
refused instead, in one line naming what it would touch; the world is as it was.

The rule, pair by pair, with the distances PyBullet's ``getClosestPoints``
gives between the new object and every body already there (as
:mod:`armfleet.physics.start_clearance` asks them for a new arm):

- **two bodies that never move** (a static object against the floor, another
  static object, or an arm's base piece): anything goes. The engine computes no
  contact between fixed bodies, so a table built of overlapping boxes, a
  platform sunk into the floor or an arm standing on a table harms nobody.
- **an arm** (any other link): the arm's own clearance,
  :data:`~armfleet.physics.start_clearance.CLEARANCE_M`. The same pair is judged the same
  whichever comes first: an arm is refused next to an object exactly where the
  object is refused next to the arm. That is what lets a launch spec's check
  place its objects before its arms while ``launch`` adds them after.
- **the floor or another object**, when one of the two can move: it may rest
  on it, sinking at most :data:`RESTING_OVERLAP_M`; deeper is an overlap.

Refused: :class:`~armfleet.errors.ObjectCollision` naming the deepest offending
pair. :meth:`armfleet.World.add_object` asks this (so the Python API, the CLI's
``add-object``, the live API and ``launch`` all do), and a launch spec's check
asks it of the spec's objects in its scratch world.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from armfleet.errors import ObjectCollision
from armfleet.objects.arm_path_clearance import ArmMotion, check_clear_of_motions
from armfleet.objects.object_spec import ObjectSpec
from armfleet.objects.world_object import WorldObject
from armfleet.physics.start_clearance import CLEARANCE_M, BodyKind, Neighbour, closest_pairs
from armfleet.runtime.lifetime import Lifetime

#: How far a new object may sink into the floor or an object it rests on [m]. The
#: solver pushes it out at about 80 mm/s per mm of overlap, and up to 2 mm it just
#: moves out by the overlap; from 3 mm on it is thrown (10 mm: a 33 mm jump). A
#: moving mesh collides as its convex hull, whose 1 mm margin makes one placed
#: exactly on the floor overlap it by 1 mm. Measured with boxes, cylinders,
#: spheres and meshes of 0.5 kg on the floor and on a static table, 1 ms steps.
RESTING_OVERLAP_M = 2e-3


def object_offences(
    client: int, body_id: int, static: bool, neighbours: Iterable[Neighbour]
) -> list[tuple[float, float, Neighbour, int]]:
    """Every pair of the new object (``body_id``) with a neighbour that breaks the rule:
    ``(distance [m], smallest allowed distance [m], neighbour, its link)``, deepest first."""
    found: list[tuple[float, float, Neighbour, int]] = []
    for other in neighbours:
        if other.body_id == body_id:
            continue
        if static and other.fixed_links >= other.links.keys():
            # Neither ever moves, so nothing is asked of PyBullet: its getClosestPoints
            # crashed the process (SIGSEGV) for some dense static meshes on the floor
            # (a 179k-triangle height field), and the answer was thrown away anyway.
            continue
        allowed = CLEARANCE_M if other.kind is BodyKind.ARM else -RESTING_OVERLAP_M
        for _, link, distance in closest_pairs(client, body_id, other.body_id, CLEARANCE_M):
            if static and link in other.fixed_links:
                continue  # neither ever moves
            if distance < allowed:
                found.append((distance, allowed, other, link))
    return sorted(found, key=lambda offence: offence[0])


def check_object_clearance(
    client: int,
    name: str,
    body_id: int,
    static: bool,
    neighbours: Iterable[Neighbour],
    outcome: str = "nothing was added",
) -> None:
    """Raise if the object ``name`` (``body_id``; ``static`` if it has no mass) breaks
    the rule of this module against any of the ``neighbours``.

    Raises:
        ObjectCollision: naming the deepest offence: the arm and link, object or
            ``ground``, and the distance.
    """
    offences = object_offences(client, body_id, static, neighbours)
    if offences:
        distance, allowed, other, link = offences[0]
        raise ObjectCollision(
            name, other.name, other.links.get(link, ""), distance, allowed, outcome
        )


def place_clear_object(
    client: int,
    spec: ObjectSpec,
    neighbours: Iterable[Neighbour],
    on_teleport: Callable[[WorldObject], None] | None = None,
    lifetime: Lifetime | None = None,
    on_remove: Callable[[str], None] | None = None,
    motions: Iterable[ArmMotion] = (),
) -> WorldObject:
    """Make the object ``spec`` describes, if it breaks no rule of this module where it is,
    nor stands in the remaining path of a moving arm (``motions``, see
    :mod:`armfleet.objects.arm_path_clearance`).

    Raises:
        ObjectCollision: it would; its body is removed again.
        ObjectInArmPath: a moving arm would pass through it or too close; its body is
            removed again.
        ObjectError: PyBullet cannot load its mesh.
    """
    obj = WorldObject(spec, client, on_teleport, lifetime, on_remove)
    try:
        check_object_clearance(client, obj.name, obj.body_id, obj.is_static, neighbours)
        check_clear_of_motions(client, obj.name, obj.body_id, motions)
    except BaseException:
        obj.discard_body()
        raise
    return obj
