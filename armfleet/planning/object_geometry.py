"""Collision shapes (coal) of scene objects, the same shapes PyBullet collides."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from armfleet.objects import WorldObject
from armfleet.objects.object_spec import Shape


def object_shape(obj: WorldObject) -> coal.CollisionGeometry:
    """The coal geometry of ``obj`` in its own frame.

    A box, cylinder (axis z) or sphere as it is; a mesh as PyBullet collides it:
    a moving mesh as its convex hull, a static one as its triangles.
    """
    spec = obj.spec
    if spec.shape is Shape.BOX:
        return coal.Box(*spec.size)
    if spec.shape is Shape.CYLINDER:
        radius, length = spec.size
        return coal.Cylinder(radius, length)
    if spec.shape is Shape.SPHERE:
        return coal.Sphere(spec.size[0])
    loader = coal.MeshLoader()
    mesh = loader.load(str(spec.mesh), np.full(3, spec.scale))
    if spec.is_static:
        return mesh
    return convex_hull(mesh)


def convex_hull(mesh: coal.BVHModelBase) -> coal.CollisionGeometry:
    """The convex hull of a triangle mesh (PyBullet collides moving meshes so)."""
    mesh.buildConvexHull(True, "Qt")
    return mesh.convex


def object_placement(obj: WorldObject) -> pin.SE3:
    """Where ``obj`` is now, as a Pinocchio placement in the world."""
    pose = obj.pose
    return pin.SE3(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))
