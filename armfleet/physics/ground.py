"""The floor of a world: a static slab whose top face is the plane z = 0.

A slab, not PyBullet's infinite plane: a plane's bounding box spans the world,
so the broadphase pairs it with every link of every arm and each pair costs a
narrowphase test at every step (about 7 µs per Panda per step). The slab's
box only meets the links near the floor. It is 2 km wide: anything placed
more than 1 km from the origin has no floor under it.
"""

from __future__ import annotations

import pybullet as p

#: Half the side of the square floor [m].
GROUND_HALF_SIDE_M = 1000.0
#: Half the thickness of the slab under z = 0 [m].
GROUND_HALF_THICKNESS_M = 0.5


def create_ground(client: int) -> int:
    """Add the floor to the PyBullet world ``client``; return its body id."""
    shape = p.createCollisionShape(
        p.GEOM_BOX,
        halfExtents=[GROUND_HALF_SIDE_M, GROUND_HALF_SIDE_M, GROUND_HALF_THICKNESS_M],
        physicsClientId=client,
    )
    return int(
        p.createMultiBody(
            0.0,
            shape,
            basePosition=[0.0, 0.0, -GROUND_HALF_THICKNESS_M],
            physicsClientId=client,
        )
    )
