"""The reference collision model of a world for the planning benchmarks: every arm and
object in one Pinocchio model with coal geometry, checked with Pinocchio's broadphase.

What counts as a collision, as in PyBullet (:mod:`armfleet.physics.collision_filter`):
every pair of collision objects except two on one joint (so two static things never
count), two on a parent and child joint, and the link pairs that never touch (sampled).
Meshes are replaced by their convex hulls: PyBullet collides a mesh as its convex
hull too. The floor is a half-space, the objects are coal boxes, cylinders and
spheres where they stand. Fingers are not planned: they stay where the world has them.

One model holds any number of :class:`Checker` s, each with its own margin.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterable
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

import armfleet
from armfleet.messages import FloatArray
from armfleet.objects import ObjectSpec, Shape

FLOOR = "floor"


@dataclass(frozen=True)
class ArmJoints:
    """Where one arm's planned joints sit in the combined configuration.

    Attributes:
        name: arm name.
        q_indices: index of each arm joint (chain order) in the combined ``q``.
        lower: lower position limits [rad].
        upper: upper position limits [rad].
    """

    name: str
    q_indices: tuple[int, ...]
    lower: FloatArray
    upper: FloatArray


class CellModel:
    """Every arm and object of ``world`` in one Pinocchio model, at the world's present state.

    Args:
        world: a world whose arms and objects are to be modelled (read once).

    Raises:
        ValueError: a mesh object (the benchmarks' cells have none).
    """

    def __init__(self, world: armfleet.World) -> None:
        model = pin.Model()
        geom = pin.GeometryModel()
        fixed: dict[str, float] = {}
        ignored: set[frozenset[str]] = set()
        owners: dict[str, str] = {}  # geometry object -> its arm (objects and floor: none)
        for arm in world.arms.values():
            urdf = arm.description.urdf
            arm_model = pin.buildModelFromXML(urdf)
            arm_geom = pin.buildGeomFromUrdfString(arm_model, urdf, pin.GeometryType.COLLISION)
            # Every arm's URDF has a frame "world": appendModel refuses two of one name.
            world_frame = arm_model.getFrameId("world")
            arm_model.frames[world_frame].name = f"{arm.name}__world"
            model, geom = pin.appendModel(model, arm_model, geom, arm_geom, 0, pin.SE3.Identity())
            owners.update((obj.name, arm.name) for obj in arm_geom.geometryObjects)
            if arm.has_gripper:
                for joint in arm_model.names[1:]:
                    if joint not in arm.joint_names:  # a finger: half the opening each
                        fixed[joint] = arm.gripper.width / 2
            ignored.update(frozenset(pair) for pair in arm.description.ignored_contacts)
        for obj in geom.geometryObjects:
            if isinstance(obj.geometry, coal.BVHModelBase):
                obj.geometry.buildConvexHull(True, "Qt")
                obj.geometry = obj.geometry.convex
        floor = coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0)
        geom.addGeometryObject(pin.GeometryObject(FLOOR, 0, 0, pin.SE3.Identity(), floor))
        for name, thing in world.objects.items():
            spec = thing.spec
            placement = pin.SE3(thing.pose)
            geom.addGeometryObject(pin.GeometryObject(name, 0, 0, placement, _shape(spec)))
        self._model = model
        self._geom = geom
        self._add_pairs(ignored, owners)
        self._arms = {
            arm.name: ArmJoints(
                arm.name,
                tuple(model.joints[model.getJointId(j)].idx_q for j in arm.joint_names),
                np.array(arm.joint_limits[0]),
                np.array(arm.joint_limits[1]),
            )
            for arm in world.arms.values()
        }
        q = pin.neutral(model)
        for arm in world.arms.values():
            q[list(self._arms[arm.name].q_indices)] = arm.positions
        for joint, value in fixed.items():
            q[model.joints[model.getJointId(joint)].idx_q] = value
        self._q = q

    def _add_pairs(self, ignored: set[frozenset[str]], owners: dict[str, str]) -> None:
        """Every pair but: two on one joint (joint 0: two static things), two of one arm
        one joint apart, and pairs never seen touching (the descriptions' ignored_contacts)."""
        model, geom = self._model, self._geom
        objects = geom.geometryObjects
        self._unchecked: set[frozenset[str]] = set()
        for i, a in enumerate(objects):
            for j in range(i + 1, len(objects)):
                b = objects[j]
                bodies = frozenset((self._body(a), self._body(b)))
                ja, jb = a.parentJoint, b.parentJoint
                same_arm = owners.get(a.name, a.name) == owners.get(b.name, b.name)
                adjacent = same_arm and (model.parents[ja] == jb or model.parents[jb] == ja)
                if ja == jb or adjacent or bodies in ignored:
                    self._unchecked.add(bodies)
                else:
                    geom.addCollisionPair(pin.CollisionPair(i, j))

    def _body(self, obj: pin.GeometryObject) -> str:
        """The link a geometry object belongs to, or the object's own name (floor, objects)."""
        if obj.parentJoint == 0 and obj.parentFrame == 0:
            return str(obj.name)
        return str(self._model.frames[obj.parentFrame].name)

    @property
    def unchecked_pairs(self) -> set[frozenset[str]]:
        """Pairs of bodies (link names; object names; ``"floor"``) never checked."""
        return set(self._unchecked)

    @property
    def model(self) -> pin.Model:
        return self._model

    @property
    def pair_count(self) -> int:
        """Collision pairs checked per state."""
        return len(self._geom.collisionPairs)

    @property
    def arms(self) -> dict[str, ArmJoints]:
        return dict(self._arms)

    @property
    def q(self) -> FloatArray:
        """The combined configuration of the world when the model was made (fingers included)."""
        return np.array(self._q)

    def indices(self, arms: Iterable[str]) -> list[int]:
        """Indices in ``q`` of the planned joints of ``arms``, in that order."""
        return [i for name in arms for i in self._arms[name].q_indices]

    def checker(self, margin_m: float) -> Checker:
        """A collision checker on this model that counts pairs closer than ``margin_m``."""
        return Checker(self, self._geom, margin_m)


class Checker:
    """Collision checks of combined configurations with one margin, via the broadphase.

    Args:
        cell: the model.
        geom: its geometry.
        margin_m: pairs closer than this count as colliding [m] (0: only touching).
    """

    def __init__(self, cell: CellModel, geom: pin.GeometryModel, margin_m: float) -> None:
        self._model = cell.model
        self._data = self._model.createData()
        self._geom = geom
        self._gdata = pin.GeometryData(geom)
        for request in self._gdata.collisionRequests:
            request.security_margin = margin_m
            request.num_max_contacts = 1
        self._manager = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(
            self._model, geom, self._gdata
        )
        self.margin_m = margin_m
        #: States checked so far, and the wall time spent in the checks [s].
        self.checks = 0
        self.seconds = 0.0

    def collides(self, q: FloatArray) -> bool:
        """Whether the combined configuration ``q`` has any pair closer than the margin."""
        started = time.perf_counter()
        hit = bool(pin.computeCollisions(self._model, self._data, self._manager, q, True))
        self.seconds += time.perf_counter() - started
        self.checks += 1
        return hit

    def colliding_pair(self, q: FloatArray) -> tuple[str, str] | None:
        """Names of the first two objects closer than the margin at ``q``, or None."""
        if not self.collides(q):
            return None
        # Pair by pair, stopping at the first: every result up to it is fresh (the
        # broadphase leaves the results of pairs it culls as they were).
        pin.computeCollisions(self._model, self._data, self._geom, self._gdata, q, True)
        for k, result in enumerate(self._gdata.collisionResults):
            if result.isCollision():
                pair = self._geom.collisionPairs[k]
                names = (
                    self._geom.geometryObjects[pair.first].name,
                    self._geom.geometryObjects[pair.second].name,
                )
                return names
        return None

    def first_contact_on_path(
        self, q_full: FloatArray, indices: list[int], waypoints: list[FloatArray], step: float
    ) -> float | None:
        """Where a piecewise-linear path first collides, as the joint-space distance along it.

        Args:
            q_full: combined configuration for the joints not planned.
            indices: indices in ``q`` of the planned joints.
            waypoints: the path's states over those joints.
            step: largest joint-space distance between two checked states [rad].

        Returns:
            Distance along the path of the first colliding state [rad], or None.
        """
        q = q_full.copy()
        travelled = 0.0
        for a, b in itertools.pairwise(waypoints):
            length = float(np.linalg.norm(b - a))
            count = max(1, int(np.ceil(length / step)))
            for k in range(count + 1):
                if k == 0 and travelled > 0:
                    continue  # the previous segment's end
                q[indices] = a + (b - a) * (k / count)
                if self.collides(q):
                    return travelled + length * k / count
            travelled += length
        return None


def _shape(spec: ObjectSpec) -> coal.CollisionGeometry:
    if spec.shape is Shape.BOX:
        return coal.Box(*spec.size)
    if spec.shape is Shape.CYLINDER:
        return coal.Cylinder(spec.size[0], spec.size[1])
    if spec.shape is Shape.SPHERE:
        return coal.Sphere(spec.size[0])
    raise ValueError(f"object {spec.name!r}: shape {spec.shape.value} is not modelled here")
