"""A scene object in the PyBullet world: its body, and its pose as measured after a step.

Poses are read from PyBullet lazily: at most once per step, and only when
someone asks (``/tf`` listeners, the viewer, user code), so idle objects cost
the simulation nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin
import pybullet as p

from armfleet.checks.real_numbers import is_real_vector
from armfleet.errors import ObjectError, UnknownObject
from armfleet.messages import FloatArray
from armfleet.objects.object_spec import ObjectSpec, Shape, pose_matrix
from armfleet.physics.body_removal import remove_body
from armfleet.physics.link_damping import disable_link_damping
from armfleet.runtime.lifetime import Lifetime, while_alive


class WorldObject:
    """One box, cylinder, sphere or mesh in a world; made by :meth:`armfleet.World.add_object`.

    Args:
        spec: what it is (checked).
        client: PyBullet client id of the world.
        on_teleport: called with the object after :meth:`set_pose` moved it; if it
            raises (the new pose is refused), the object goes back where it was.
        on_remove: called with the object's name by :meth:`remove`: the world's own
            removal (body, frame, contacts, viewer). Without it, :meth:`remove` takes
            the body out of the physics engine only.
        lifetime: its own, a child of its world's (see :mod:`armfleet.runtime.lifetime`),
            ended by :meth:`remove`: once the world is closed, reading or moving the
            object raises :class:`~armfleet.errors.WorldClosed`, once it is removed
            :class:`~armfleet.errors.UnknownObject` (listing the objects there are).
            What it *is* (name, shape, size, mass, friction, colour, mesh, spec)
            stays readable.
    """

    def __init__(
        self,
        spec: ObjectSpec,
        client: int,
        on_teleport: Callable[[WorldObject], None] | None = None,
        lifetime: Lifetime | None = None,
        on_remove: Callable[[str], None] | None = None,
    ) -> None:
        self._spec = spec
        self._on_remove = on_remove
        self._lifetime = lifetime or Lifetime(lambda: UnknownObject(spec.name, []))
        self._client = client
        self._on_teleport = on_teleport
        try:
            self._shape_id = _collision_shape(spec, client)
        except p.error:  # PyBullet raises, or returns -1, for a file it cannot use
            self._shape_id = -1
        if self._shape_id < 0:
            raise ObjectError(spec.name, "mesh", f"PyBullet cannot load {spec.mesh}")
        position, orientation = _position_quaternion(spec.matrix())
        self._body_id: int = p.createMultiBody(
            baseMass=spec.mass_kg,
            baseCollisionShapeIndex=self._shape_id,
            basePosition=position,
            baseOrientation=orientation,
            physicsClientId=client,
        )
        p.changeDynamics(
            self._body_id,
            -1,
            lateralFriction=spec.friction,
            spinningFriction=spec.spinning_friction_m,
            rollingFriction=spec.rolling_friction_m,
            physicsClientId=client,
        )
        disable_link_damping(self._body_id, client)  # no drag that physics lacks
        self._pose: FloatArray | None = None
        self._removed = False

    # -- what it is ---------------------------------------------------------------------
    @property
    def name(self) -> str:
        """Object name, also its frame on ``/tf`` (child of ``world``)."""
        return self._spec.name

    @property
    def shape(self) -> Shape:
        return self._spec.shape

    @property
    def size(self) -> tuple[float, ...]:
        """Box (x, y, z) full extents; cylinder (radius, length); sphere (radius,);
        mesh: extents of the scaled mesh's bounding box [m]."""
        return self._spec.size

    @property
    def mass(self) -> float:
        """Mass [kg]; 0 for a static object."""
        return self._spec.mass_kg

    @property
    def is_static(self) -> bool:
        """Whether it is fixed in the world (mass 0), like a table."""
        return self._spec.is_static

    @property
    def friction(self) -> float:
        """Lateral friction coefficient."""
        return self._spec.friction

    @property
    def color(self) -> tuple[float, float, float, float]:
        """RGBA, each in [0, 1]."""
        return self._spec.color

    @property
    def mesh(self) -> Path | None:
        """Absolute path of the mesh file (mesh objects), else None."""
        return self._spec.mesh

    @property
    def spec(self) -> ObjectSpec:
        """Everything it was made from (its pose: the initial one)."""
        return self._spec

    @property
    def lifetime(self) -> Lifetime:
        """Ended once the object is removed or its world closed."""
        return self._lifetime

    @property
    def removed(self) -> bool:
        return self._removed

    @property
    @while_alive
    def body_id(self) -> int:
        """PyBullet body id (for inspection; move it with :meth:`set_pose`); a removed
        object's id may be a new body's, so it raises like the rest."""
        return self._body_id

    # -- where it is --------------------------------------------------------------------
    @property
    @while_alive
    def pose(self) -> FloatArray:
        """4x4 pose of the object's frame in ``world``, as measured after the last step [m]."""
        if self._pose is None:
            position, orientation = p.getBasePositionAndOrientation(
                self._body_id, physicsClientId=self._client
            )
            pose = np.eye(4)
            pose[:3, :3] = np.reshape(p.getMatrixFromQuaternion(orientation), (3, 3))
            pose[:3, 3] = position
            self._pose = pose
        return self._pose.copy()

    @property
    @while_alive
    def position(self) -> FloatArray:
        """(x, y, z) of the object's frame in ``world`` [m]."""
        return self.pose[:3, 3]

    @property
    @while_alive
    def velocity(self) -> FloatArray:
        """Linear velocity of the object's frame in ``world`` [m/s]."""
        linear, _ = p.getBaseVelocity(self._body_id, physicsClientId=self._client)
        return np.array(linear, dtype=float)

    @property
    @while_alive
    def angular_velocity(self) -> FloatArray:
        """Angular velocity in ``world`` [rad/s]."""
        _, angular = p.getBaseVelocity(self._body_id, physicsClientId=self._client)
        return np.array(angular, dtype=float)

    @while_alive
    def set_pose(self, at: Sequence[float], rpy_deg: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Teleport the object to ``at`` [m], ``rpy_deg`` [deg], at rest (for tests, scenarios).

        Call it between steps (from the stepping thread, or through
        :meth:`armfleet.World.submit`).

        Raises:
            ObjectError: not a finite pose.
            ObjectCollision: in a world, it would touch an arm or overlap something
                there (the rule of :mod:`armfleet.objects.object_clearance`, as for a new
                object); it stays where it was, moving as it was.
        """
        if not (is_real_vector(at) and is_real_vector(rpy_deg)) or not (
            len(at) == len(rpy_deg) == 3 and all(math.isfinite(v) for v in [*at, *rpy_deg])
        ):
            raise ObjectError(
                self.name, "set_pose", "give at=(x, y, z) [m] and rpy_deg=(r, p, y), finite"
            )
        position, orientation = p.getBasePositionAndOrientation(
            self._body_id, physicsClientId=self._client
        )
        velocity = p.getBaseVelocity(self._body_id, physicsClientId=self._client)
        self._place(*_position_quaternion(pose_matrix(at, rpy_deg)), ([0, 0, 0], [0, 0, 0]))
        if self._on_teleport is not None:
            try:
                self._on_teleport(self)
            except BaseException:  # refused where it would go: back where it was
                self._place(position, orientation, velocity)
                raise

    def _place(
        self,
        position: Sequence[float],
        orientation: Sequence[float],
        velocity: tuple[Sequence[float], Sequence[float]],
    ) -> None:
        p.resetBasePositionAndOrientation(
            self._body_id, position, orientation, physicsClientId=self._client
        )
        p.resetBaseVelocity(self._body_id, *velocity, physicsClientId=self._client)
        self._pose = None

    @while_alive
    def stale(self) -> None:
        """Forget the measured pose: the world has stepped."""
        self._pose = None

    @while_alive
    def remove(self) -> None:
        """Take the object out of its world, as :meth:`armfleet.World.remove_object` does:
        body, frame, contacts and viewer.

        Raises:
            UnknownObject: removed already; WorldClosed: its world is closed.
        """
        if self._on_remove is not None:
            self._on_remove(self.name)  # the world's removal, which discards the body
        else:
            self.discard_body()

    @while_alive
    def discard_body(self) -> None:
        """Take the body out of the physics engine and end the handle; what the world
        keeps of it (frame, contacts) is the caller's (:class:`ObjectSet`) to drop.

        Raises:
            UnknownObject: removed already; WorldClosed: its world is closed.
        """
        self._lifetime.end()  # its handles raise UnknownObject from now on
        self._removed = True
        # Its collision shape stays: PyBullet refuses to remove a shape a body used.
        remove_body(self._client, self._body_id)

    def __repr__(self) -> str:
        kind = "static" if self.is_static else f"{self.mass:g} kg"
        return f"WorldObject({self.name!r}, {self.shape.value}, size={self.size}, {kind})"


def _collision_shape(spec: ObjectSpec, client: int) -> int:
    if spec.shape is Shape.BOX:
        half = [s / 2 for s in spec.size]
        return int(p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client))
    if spec.shape is Shape.CYLINDER:
        radius, length = spec.size
        return int(
            p.createCollisionShape(
                p.GEOM_CYLINDER, radius=radius, height=length, physicsClientId=client
            )
        )
    if spec.shape is Shape.SPHERE:
        radius = spec.size[0]
        return int(p.createCollisionShape(p.GEOM_SPHERE, radius=radius, physicsClientId=client))
    # A static mesh keeps its concave shape (a bin, a shelf); a moving one gets its convex hull.
    flags = p.GEOM_FORCE_CONCAVE_TRIMESH if spec.is_static else 0
    return int(
        p.createCollisionShape(
            p.GEOM_MESH,
            fileName=str(spec.mesh),
            meshScale=[spec.scale] * 3,
            flags=flags,
            physicsClientId=client,
        )
    )


def _position_quaternion(matrix: FloatArray) -> tuple[list[float], list[float]]:
    """(position, quaternion x, y, z, w) of a 4x4 pose."""
    quaternion = pin.Quaternion(np.ascontiguousarray(matrix[:3, :3])).coeffs()
    return matrix[:3, 3].tolist(), quaternion.tolist()
