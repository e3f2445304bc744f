"""Scene objects: boxes, cylinders, spheres and meshes that arms push, pick and place.

Made by :meth:`armfleet.World.add_object` or a launch spec's ``objects:``;
simulated by PyBullet, framed on ``/tf`` (``world -> <object>``), reported on
``/collisions`` and drawn by the viewer.

Rule: imports :mod:`armfleet.description`, :mod:`armfleet.frames`,
:mod:`armfleet.physics`, :mod:`armfleet.runtime` and below; never an arm or the world.
"""

from armfleet.objects.object_set import ObjectSet
from armfleet.objects.object_spec import ObjectSpec, Shape, object_spec
from armfleet.objects.world_object import WorldObject

__all__ = ["ObjectSet", "ObjectSpec", "Shape", "WorldObject", "object_spec"]
