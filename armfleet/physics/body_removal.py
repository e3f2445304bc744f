"""Taking a body out of a PyBullet world without leaving its collision filters behind.

PyBullet hands a removed body's id to the next body loaded, and the pair filters set with
``setCollisionFilterPair`` are kept by id, not by body: they outlive the body. A box added
after an arm was removed could take the arm's id and inherit "no contact with the floor"
for the arm's base links, and fall through the floor. Before a body goes, every pair it
can be part of is set back to colliding, which is what PyBullet does for a pair without a
filter (armfleet loads every body with the default collision group and mask).
"""

from __future__ import annotations

import pybullet as p


def remove_body(client: int, body_id: int) -> None:
    """Re-enable every collision pair ``body_id`` can be part of, then remove it."""
    own = _links(client, body_id)
    for i, a in enumerate(own):
        for b in own[i + 1 :]:
            p.setCollisionFilterPair(body_id, body_id, a, b, 1, physicsClientId=client)
    for index in range(p.getNumBodies(physicsClientId=client)):
        other = p.getBodyUniqueId(index, physicsClientId=client)
        if other == body_id:
            continue
        for link in own:
            for other_link in _links(client, other):
                p.setCollisionFilterPair(
                    body_id, other, link, other_link, 1, physicsClientId=client
                )
    p.removeBody(body_id, physicsClientId=client)


def _links(client: int, body_id: int) -> list[int]:
    """The base (-1) and every link of a body."""
    return [-1, *range(p.getNumJoints(body_id, physicsClientId=client))]
