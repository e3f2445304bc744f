"""The planning scene: every arm, object and the floor of a world as one Pinocchio model.

The arms' Pinocchio models are appended into one model whose configuration is every
arm's movable joints; their collision meshes become convex hulls (as PyBullet collides
them), scene objects are coal boxes, cylinders, spheres and meshes, and the floor is a
half-space at z = 0. A held object is attached to the joint of the hand that holds it.

Which pairs count:

- not two geometries of one rigid piece, nor of two pieces one joint apart (adjacent);
- not pairs never seen touching in sampled configurations (the description's
  ``ignored_contacts``: :mod:`armfleet.physics.contact_pairs`);
- not a held object against its gripper (the hand and the fingers);
- and, per request (:meth:`PlanningScene.checker`), only pairs in which something moves
  with the planned joints: two things that stand still cannot start to collide.

Between different bodies a pair collides when closer than the clearance (coal's
``security_margin``); within one arm when closer than the arm's own margin. To both,
each geometry adds the collision margin the physics gives its shape
(:func:`physics_margin`): PyBullet collides a convex hull grown by 1 mm, so a state clear
by the clearance here is clear by it in PyBullet too, at any clearance allowed.

Checks run in compiled code: ``cpp/planning_check.cpp``
(:mod:`~armfleet.planning.compiled_check`) where the kernel is built and knows the
scene's joints and shapes; otherwise, and as the reference, Pinocchio's broadphase
manager (a dynamic AABB tree) over the active pairs.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import coal
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from armfleet.description.mesh_units import mesh_unit_m
from armfleet.messages import FloatArray
from armfleet.planning.compiled_check import compiled_scene_check, placement_numbers
from armfleet.planning.object_geometry import convex_hull

GROUND = "ground"
#: The floor: a slab whose top is z = 0 [m].
FLOOR_SIZE_M = 200.0
FLOOR_THICKNESS_M = 1.0
#: Largest margin between two links of one arm [m] (the clearance, if smaller).
SELF_CLEARANCE_M = 0.01
#: Wider margins of the "far from everything" check [m]: between bodies, within an arm.
FAR_CLEARANCE_M = 0.05
FAR_SELF_CLEARANCE_M = 0.03
#: Bullet's collision margin around a convex hull or a triangle mesh [m]: PyBullet's URDF
#: importer (``gUrdfDefaultCollisionMargin``) and ``createCollisionShape`` give it to every
#: mesh, and to a URDF cylinder, which it makes a convex hull of points on its rims.
BULLET_MARGIN_M = 0.001


def physics_margin(shape: coal.CollisionGeometry, from_urdf: bool) -> float:
    """How far PyBullet's shape of ``shape`` may reach beyond it [m]: Bullet's collision
    margin for a mesh (a convex hull or triangles) and for a URDF's cylinder; 0 for a box,
    a sphere and a capsule, whose margins Bullet keeps inside them, and for the cylinders
    of scene objects (Bullet's own cylinder, margin inside too)."""
    if isinstance(shape, (coal.ConvexBase, coal.BVHModelBase)):
        return BULLET_MARGIN_M
    if isinstance(shape, coal.Cylinder) and from_urdf:
        return BULLET_MARGIN_M
    return 0.0


@dataclass(frozen=True)
class ArmGeometry:
    """One arm's kinematics and collision geometry, ready to be appended into a scene.

    Attributes:
        name: arm name.
        model: its Pinocchio model (root ``world`` frame renamed ``<name>__world``).
        geometry: its collision geometry, meshes as convex hulls.
        controlled_joints: the joints the planner moves (``Arm.joint_names``).
        ignored_pairs: link pairs that never touch (the description's ``ignored_contacts``).
        hand_joint: the joint the fingers hang from (a held object is attached to it),
            or None without a gripper.
    """

    name: str
    model: pin.Model
    geometry: pin.GeometryModel
    controlled_joints: tuple[str, ...]
    ignored_pairs: frozenset[frozenset[str]]
    hand_joint: str | None


@dataclass(frozen=True)
class SceneObject:
    """One object of the scene.

    Attributes:
        name: object name.
        shape: its coal geometry.
        placement: its pose in the world, or, when ``held_by`` is set, in the
            frame of that arm's hand joint.
        held_by: the arm whose gripper holds it, or None.
    """

    name: str
    shape: coal.CollisionGeometry
    placement: pin.SE3
    held_by: str | None = None


def arm_geometry(
    name: str,
    urdf: str,
    model: pin.Model,
    controlled_joints: Sequence[str],
    ignored_pairs: Iterable[tuple[str, str]],
    finger_joints: Sequence[str],
) -> ArmGeometry:
    """Build the collision geometry of one arm from the URDF text PyBullet loaded.

    Args:
        name: arm name.
        urdf: its URDF text (absolute mesh paths).
        model: its Pinocchio model (from the same text; copied, not changed).
        controlled_joints: prefixed names of the joints planning moves.
        ignored_pairs: link pairs whose contacts don't count (never seen touching).
        finger_joints: prefixed names of its finger joints (empty without a gripper).
    """
    own = model.copy()
    for index, frame in enumerate(own.frames):
        if frame.name in ("world", "universe"):
            renamed = own.frames[index]
            renamed.name = f"{name}__{frame.name}"
            own.frames[index] = renamed
    geometry = pin.buildGeomFromUrdfString(own, urdf, pin.GeometryType.COLLISION)
    for item in geometry.geometryObjects:
        if isinstance(item.geometry, coal.BVHModelBase):
            unit = mesh_unit_m(item.meshPath)
            if unit != 1.0:  # coal ignores a COLLADA unit; PyBullet applies it
                item.meshScale = item.meshScale * unit
                item.geometry = coal.MeshLoader().load(item.meshPath, item.meshScale)
            item.geometry = convex_hull(item.geometry)
    hand = None
    if finger_joints:
        hand = own.names[own.parents[own.getJointId(finger_joints[0])]]
    return ArmGeometry(
        name,
        own,
        geometry,
        tuple(controlled_joints),
        frozenset(frozenset(pair) for pair in ignored_pairs),
        hand,
    )


class PlanningScene:
    """A world's arms, objects and floor at one instant, for collision checks.

    Args:
        arms: the arms' geometries, in the world's order.
        objects: the scene objects.
        clearance_m: margin between different bodies [m].
    """

    def __init__(
        self, arms: Sequence[ArmGeometry], objects: Sequence[SceneObject], clearance_m: float
    ) -> None:
        self.clearance_m = clearance_m
        #: Margin between two links of one arm [m]: a margin on every pair is what lets
        #: :mod:`armfleet.planning.path_check` prove a path contact-free.
        self.self_clearance_m = min(clearance_m, SELF_CLEARANCE_M)
        self.arm_names = tuple(arm.name for arm in arms)
        model, geometry = pin.Model(), pin.GeometryModel()
        for arm in arms:
            model, geometry = pin.appendModel(
                model, arm.model, geometry, arm.geometry, 0, pin.SE3.Identity()
            )
        self._arms = {arm.name: arm for arm in arms}
        #: Per geometry: the body it belongs to (arm or object name, or ground).
        owners = [self._arm_of(model, item.parentJoint) for item in geometry.geometryObjects]
        # The floor as a slab, as PyBullet's: a half-space's bounding box would not grow by
        # the margin in the broadphase, which then misses what is within it of the floor.
        floor = pin.SE3(np.eye(3), np.array([0.0, 0.0, -FLOOR_THICKNESS_M / 2]))
        slab = coal.Box(FLOOR_SIZE_M, FLOOR_SIZE_M, FLOOR_THICKNESS_M)
        geometry.addGeometryObject(pin.GeometryObject(GROUND, 0, floor, slab))
        owners.append(GROUND)
        for obj in objects:
            joint = 0
            if obj.held_by is not None:
                hand = self._arms[obj.held_by].hand_joint
                assert hand is not None  # only arms with a gripper hold things
                joint = model.getJointId(hand)
            item = pin.GeometryObject(obj.name, joint, obj.placement, obj.shape)
            geometry.addGeometryObject(item)
            owners.append(obj.name)
        self.model, self.geometry = model, geometry
        self._owners = owners
        #: Indices of the objects' geometries (their placements change between requests).
        self.object_geometries = [geometry.getGeometryId(obj.name) for obj in objects]
        arm_count = len(owners) - 1 - len(objects)  # the arms' geometries come first
        #: Per geometry, how far PyBullet's shape may reach beyond it [m].
        self.physics_margins = np.array(
            [
                physics_margin(item.geometry, index < arm_count)
                for index, item in enumerate(geometry.geometryObjects)
            ]
        )
        self._held = {obj.name: obj.held_by for obj in objects if obj.held_by is not None}
        self._checkers: dict[tuple[Any, ...], CollisionChecker] = {}
        self._add_pairs()
        same_body = np.array(
            [owners[pair.first] == owners[pair.second] for pair in geometry.collisionPairs],
            dtype=bool,
        )
        #: The far check's margins without the physics margins [m]: between bodies,
        #: within an arm (the proof sizes its long steps with them).
        self.far_clearance_m = max(clearance_m, FAR_CLEARANCE_M)
        self.far_self_clearance_m = max(self.self_clearance_m, FAR_SELF_CLEARANCE_M)
        grown = np.array(
            [
                self.physics_margins[pair.first] + self.physics_margins[pair.second]
                for pair in geometry.collisionPairs
            ]
        ).reshape(-1)
        #: Per collision pair, its margin [m]: within one arm, between different bodies,
        #: each with the two shapes' physics margins.
        self.margins = np.where(same_body, self.self_clearance_m, clearance_m) + grown
        #: Per collision pair, the wider margin of :meth:`CollisionChecker.far` [m].
        self.far_margins = (
            np.where(same_body, self.far_self_clearance_m, self.far_clearance_m) + grown
        )
        #: The configuration of every movable joint of every arm, where they are now.
        self.positions = pin.neutral(model)
        self._columns = {
            arm.name: np.array(
                [model.joints[model.getJointId(j)].idx_q for j in arm.controlled_joints]
            )
            for arm in arms
        }
        self._all_columns = {
            arm.name: np.array(
                [model.joints[model.getJointId(n)].idx_q for n in arm.model.names[1:]]
            )
            for arm in arms
        }

    # -- what the scene holds -------------------------------------------------------------
    def columns(self, arm: str) -> npt.NDArray[np.int_]:
        """Indices into the scene's configuration of ``arm``'s controlled joints."""
        return self._columns[arm]

    def set_arm(self, arm: str, positions: FloatArray) -> None:
        """Put every movable joint of ``arm`` (its kinematics' order) at ``positions``."""
        self.positions[self._all_columns[arm]] = positions

    def set_arm_controlled(self, arm: str, positions: FloatArray) -> None:
        """Put ``arm``'s controlled joints (``Arm.joint_names`` order) at ``positions``."""
        self.positions[self._columns[arm]] = positions

    def hand_joint(self, arm: str) -> str:
        """The joint ``arm``'s fingers hang from (where a held object is attached)."""
        hand = self._arms[arm].hand_joint
        if hand is None:
            raise KeyError(f"{arm} has no gripper")
        return hand

    def set_object(self, name: str, placement: pin.SE3) -> None:
        """Move the (not held) object ``name`` to ``placement`` in the world."""
        index = self.geometry.getGeometryId(name)
        self.geometry.geometryObjects[index].placement = placement

    def body_link(self, geometry_index: int) -> str:
        """The link (prefixed) or object a geometry belongs to, for messages."""
        owner = self._owners[geometry_index]
        if owner in self._arms:
            return self._link_name(self.geometry.geometryObjects[geometry_index])
        return owner

    def owner_of(self, body_link: str) -> str:
        """The arm a link (as :meth:`body_link` names it) belongs to, or the name itself
        (an object, the floor)."""
        for arm in self._arms.values():
            if arm.model.existFrame(body_link):
                return arm.name
        return body_link

    def _arm_of(self, model: pin.Model, joint: int) -> str:
        if joint == 0:
            return ""
        name = model.names[joint]
        for arm in self._arms.values():
            if arm.model.existJointName(name):
                return arm.name
        # Fixed links hang from the universe: the geometry's name carries the prefix.
        return ""

    # -- pairs ---------------------------------------------------------------------------------
    def _add_pairs(self) -> None:
        geometry = self.geometry
        items = geometry.geometryObjects
        links = [self._link_name(item) for item in items]
        for index, owner in enumerate(self._owners):
            if owner == "":  # a fixed link of an arm: find the arm by its name's prefix
                self._owners[index] = self._arm_by_link(links[index])
        for a in range(len(items)):
            for b in range(a + 1, len(items)):
                if self._counts(a, b, links):
                    geometry.addCollisionPair(pin.CollisionPair(a, b))

    def _link_name(self, item: pin.GeometryObject) -> str:
        if item.parentFrame < len(self.model.frames):
            return str(self.model.frames[item.parentFrame].name)
        return str(item.name)  # the floor and objects: no frame of their own

    def _arm_by_link(self, link: str) -> str:
        for arm in self._arms.values():
            if arm.model.existFrame(link):
                return arm.name
        return GROUND

    def _counts(self, a: int, b: int, links: Sequence[str]) -> bool:
        items = self.geometry.geometryObjects
        joint_a, joint_b = items[a].parentJoint, items[b].parentJoint
        if joint_a == joint_b:
            return False  # one rigid piece (or both fixed in the world)
        owner_a, owner_b = self._owners[a], self._owners[b]
        if owner_a == owner_b and owner_a in self._arms:
            parents = self.model.parents
            if parents[joint_a] == joint_b or parents[joint_b] == joint_a:
                return False
            if frozenset((links[a], links[b])) in self._arms[owner_a].ignored_pairs:
                return False
        for held, other in ((owner_a, b), (owner_b, a)):
            arm = self._held.get(held)
            if arm is not None and self._in_gripper(arm, items[other].parentJoint):
                return False
        return True

    def _in_gripper(self, arm: str, joint: int) -> bool:
        """Whether ``joint`` is ``arm``'s hand joint or one hanging from it (a finger)."""
        hand = self._arms[arm].hand_joint
        if hand is None or joint == 0:
            return False
        hand_id = self.model.getJointId(hand)
        return bool(joint == hand_id or self.model.parents[joint] == hand_id)

    # -- checking --------------------------------------------------------------------------------
    def checker(self, arms: Sequence[str], compiled: bool = True) -> CollisionChecker:
        """A checker of configurations of ``arms``' controlled joints (concatenated in this
        order), the rest of the scene where it is now; ``compiled=False``: the Python
        reference check, even where the compiled one is built.

        Checkers are kept per set of arms (building one costs milliseconds: two geometry
        data and two broadphase trees); each call hands it the scene as it is now and
        starts its count of checks afresh.
        """
        key = (*arms, compiled)
        checker = self._checkers.get(key)
        if checker is None:
            checker = self._checkers[key] = CollisionChecker(self, arms, compiled)
        checker.refresh()
        return checker

    def moving_geometries(self, joints: Iterable[int]) -> npt.NDArray[np.bool_]:
        """Per geometry, whether it moves with any of the model joints ``joints``."""
        moving_joints = set(joints)
        supports = self.model.supports
        return np.array(
            [
                bool(moving_joints.intersection(supports[item.parentJoint]))
                for item in self.geometry.geometryObjects
            ]
        )

    def joint_ids(self, arms: Sequence[str]) -> list[int]:
        """Model joint ids of the controlled joints of ``arms``."""
        return [
            self.model.getJointId(name)
            for arm in arms
            for name in self._arms[arm].controlled_joints
        ]


class TooClose(NamedTuple):
    """Two links closer than their pair's margin.

    Attributes:
        first, second: the links (``<arm>_<link>``, or an object's name).
        distance_m: between them [m]; negative: inside each other.
        margin_m: what the pair must keep [m]: the clearance asked, and the physics'
            collision margins of both shapes (:func:`physics_margin`).
    """

    first: str
    second: str
    distance_m: float
    margin_m: float


class CollisionChecker:
    """Collision checks of one request: the planned arms' joints move, the rest stands.

    Each checker has its own geometry data, so that checkers of one scene don't
    disturb each other. It answers two questions: :meth:`valid` (the scene's margins,
    the clearance) and :meth:`far` (a wider margin, :data:`FAR_CLEARANCE_M`, which lets
    :mod:`~armfleet.planning.path_check` take longer steps away from obstacles).

    Both run in compiled code (:attr:`compiled`) where it can model the scene; Pinocchio's
    broadphase (the reference) otherwise.

    Args:
        scene: the scene (its current configuration is the rest of the world).
        arms: the planned arms; a state is their controlled joints, concatenated.
        compiled: use the compiled check where it is built and knows the scene.
    """

    def __init__(self, scene: PlanningScene, arms: Sequence[str], compiled: bool = True) -> None:
        self.scene = scene
        self.arms = tuple(arms)
        self.columns = np.concatenate([scene.columns(arm) for arm in arms])
        moving = scene.moving_geometries(scene.joint_ids(arms))
        pairs = scene.geometry.collisionPairs
        self.active = np.array([moving[p.first] or moving[p.second] for p in pairs], dtype=bool)
        self.data = self._data(scene.margins)
        self._managers: tuple[Any, Any, Any] | None = None  # Pinocchio's, made on first use
        self._model_data = scene.model.createData()
        self._q = scene.positions.copy()
        self._checks = 0
        #: The compiled check of this checker's pairs (``cpp/planning_check.cpp``), or None.
        self.compiled: Any = None
        if compiled:
            grown = scene.physics_margins
            pairs = [
                (
                    pair.first,
                    pair.second,
                    scene.margins[k],
                    scene.far_margins[k],
                    grown[pair.first] + grown[pair.second],
                )
                for k, pair in enumerate(scene.geometry.collisionPairs)
                if self.active[k]
            ]
            self.compiled = compiled_scene_check(scene.model, scene.geometry, pairs, self.columns)
        #: Reach bounds of the proof, with the placements of held objects they were made
        #: for (:func:`armfleet.planning.path_check.joint_levers`).
        self.levers: tuple[bytes, FloatArray] | None = None
        self.refresh()

    @property
    def checks(self) -> int:
        """How many states were checked since the last :meth:`refresh`."""
        return self._checks + (self.compiled.checks if self.compiled is not None else 0)

    def refresh(self) -> None:
        """Take the scene's configuration for the joints not planned, and count anew."""
        self._q[:] = self.scene.positions
        self._checks = 0
        if self.compiled is not None:
            compiled = self.compiled
            compiled.set_configuration(self.scene.positions)
            for index in self.scene.object_geometries:
                placement = self.scene.geometry.geometryObjects[index].placement
                compiled.set_placement(index, placement_numbers(placement))
            compiled.checks = compiled.pairs_by_volume = compiled.pairs_by_coal = 0

    def _data(self, margins: FloatArray) -> pin.GeometryData:
        data = self.scene.geometry.createData()
        for index, (margin, active) in enumerate(zip(margins, self.active, strict=True)):
            data.collisionRequests[index].security_margin = float(margin)
            data.activeCollisionPairs[index] = bool(active)
        return data

    def valid(self, state: FloatArray) -> bool:
        """Whether the planned joints at ``state`` keep the clearance from everything."""
        if self.compiled is not None:
            return bool(self.compiled.clear(state, False))
        self._checks += 1
        q = self._q
        q[self.columns] = state
        manager = self._broadphase()[0]
        return not pin.computeCollisions(self.scene.model, self._model_data, manager, q, True)

    def far(self, state: FloatArray) -> bool:
        """Whether the planned joints at ``state`` keep :attr:`PlanningScene.far_margins`."""
        if self.compiled is not None:
            return bool(self.compiled.clear(state, True))
        self._checks += 1
        q = self._q
        q[self.columns] = state
        model, data = self.scene.model, self._model_data
        return not pin.computeCollisions(model, data, self._broadphase()[1], q, True)

    def _broadphase(self) -> tuple[Any, Any]:
        """Pinocchio's broadphase managers of the margins and the far margins."""
        if self._managers is None:
            scene = self.scene
            far_data = self._data(scene.far_margins)
            self._managers = (
                pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(
                    scene.model, scene.geometry, self.data
                ),
                pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(
                    scene.model, scene.geometry, far_data
                ),
                far_data,  # kept alive with its manager
            )
        return self._managers[0], self._managers[1]

    def collision(self, state: FloatArray) -> TooClose | None:
        """The closest of the pairs closer than their margin at ``state``, or None. Pair
        by pair: slower than :meth:`valid`, for messages."""
        scene = self.scene
        q = self._q.copy()
        q[self.columns] = state
        pin.updateGeometryPlacements(scene.model, self._model_data, scene.geometry, self.data, q)
        closest: TooClose | None = None
        for index in np.flatnonzero(self.active):
            if pin.computeCollision(scene.geometry, self.data, int(index)):
                pair = scene.geometry.collisionPairs[int(index)]
                distance = pin.computeDistance(scene.geometry, self.data, int(index))
                if closest is None or distance.min_distance < closest.distance_m:
                    closest = TooClose(
                        scene.body_link(pair.first),
                        scene.body_link(pair.second),
                        float(distance.min_distance),
                        float(scene.margins[int(index)]),
                    )
        return closest
