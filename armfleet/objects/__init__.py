"""Scene objects: boxes, cylinders, spheres and meshes that arms push, pick and place.

Made by :meth:`armfleet.World.add_object` or a launch spec's ``objects:``;
simulated by PyBullet, framed on ``/tf`` (``world -> <object>``), reported on
``/collisions`` and drawn by the viewer.

Rule: imports :mod:`armfleet.description`, :mod:`armfleet.frames`,
:mod:`armfleet.physics`, :mod:`armfleet.runtime` and below; never an arm or the world.
"""

from typing import TYPE_CHECKING

# Eager: the name is also its module's, which a lazy name would leave in its place.
from armfleet.objects.object_spec import ObjectSpec, Shape, object_spec
from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.objects.object_set import ObjectSet
    from armfleet.objects.world_object import WorldObject

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ObjectSet": "armfleet.objects.object_set",
        "WorldObject": "armfleet.objects.world_object",
    },
)

__all__ = ["ObjectSet", "ObjectSpec", "Shape", "WorldObject", "object_spec"]
