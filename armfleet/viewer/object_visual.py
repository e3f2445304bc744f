"""One scene object in the viewer: its geometry under ``/meshcat/objects/<name>``.

MeshCat draws a cylinder along its y axis and scales meshes through their
node's matrix, so each node's matrix is the object's world pose times a fixed
local transform: a quarter turn about x for a cylinder (PyBullet's axis is
z), the scale for a mesh.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from armfleet.objects.object_spec import Shape
from armfleet.viewer.commands import TransformPacker, Updates

if TYPE_CHECKING:
    from armfleet.objects import WorldObject

#: Motion below which an object is not redrawn [m, or rad times 1 m].
REDRAW_TOLERANCE = 1e-6
#: Quarter turn about x: MeshCat's cylinder axis (y) onto the object's z.
CYLINDER_AXIS = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])

Pose = npt.NDArray[np.float64]


def geometry(obj: WorldObject) -> Any:
    """MeshCat geometry of ``obj`` in its own frame (before :func:`local_transform`)."""
    import meshcat.geometry as mg

    if obj.shape is Shape.BOX:
        return mg.Box(list(obj.size))
    if obj.shape is Shape.CYLINDER:
        radius, length = obj.size
        return mg.Cylinder(length, radius)
    if obj.shape is Shape.SPHERE:
        return mg.Sphere(obj.size[0])
    assert obj.mesh is not None
    if obj.mesh.suffix.lower() == ".stl":
        return mg.StlMeshGeometry.from_file(str(obj.mesh))
    return mg.ObjMeshGeometry.from_file(str(obj.mesh))


def material(obj: WorldObject) -> Any:
    """A lit material of the object's colour (transparent below alpha 1)."""
    import meshcat.geometry as mg

    red, green, blue, alpha = obj.color
    rgb = (round(red * 255) << 16) | (round(green * 255) << 8) | round(blue * 255)
    return mg.MeshLambertMaterial(color=rgb, opacity=alpha, transparent=alpha < 1.0)


def local_transform(obj: WorldObject) -> Pose:
    """What MeshCat's geometry needs after the object's pose: an axis turn or a scale."""
    if obj.shape is Shape.CYLINDER:
        return CYLINDER_AXIS.copy()
    if obj.shape is Shape.MESH:
        return np.diag([obj.spec.scale] * 3 + [1.0])
    return np.eye(4)


class ObjectVisual:
    """Draws one object in a shared ``meshcat.Visualizer`` and makes its live updates.

    Args:
        obj: the object.
        visualizer: the viewer's ``meshcat.Visualizer`` (root ``/meshcat``).
    """

    def __init__(self, obj: WorldObject, visualizer: Any) -> None:
        self.object = obj
        self.name = obj.name
        #: MeshCat path of the object's node.
        self.node = f"/meshcat/objects/{obj.name}"
        self._local = local_transform(obj)
        #: Rotation of the local transform alone (the replay animates rotations).
        self.local_rotation = self._local[:3, :3] / np.linalg.norm(self._local[:3, 0])
        self._packer = TransformPacker((self.node,))
        self._last: Pose | None = None
        node = visualizer[f"objects/{obj.name}"]
        node.set_object(geometry(obj), material(obj))
        pose = obj.pose
        node.set_transform(self.node_matrix(pose))
        self._last = pose

    def node_matrix(self, pose: Pose) -> Pose:
        """The node's matrix for the object at world ``pose``."""
        matrix: Pose = pose @ self._local
        return matrix

    def collect(self, into: Updates) -> None:
        """Add the object's new pose to ``into`` if it moved since the last call."""
        pose = self.object.pose
        last = self._last
        if last is None or float(np.max(np.abs(pose - last))) > REDRAW_TOLERANCE:
            self._packer.pack(self.node_matrix(pose)[None], into)
            self._last = pose

    def bounds(self) -> tuple[Pose, Pose]:
        """(min, max) corners [m] of a box around the object at its current pose."""
        pose = self.object.pose
        reach = float(np.linalg.norm(self.object.spec.half_extents))
        return pose[:3, 3] - reach, pose[:3, 3] + reach
