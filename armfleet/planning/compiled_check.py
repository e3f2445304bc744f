"""The planning scene handed to compiled code: one call per state checked, one per path proven.

``cpp/planning_check.cpp`` (built with the fleet kernel on ``pip install``) rebuilds a
:class:`~armfleet.planning.scene.PlanningScene` from its numbers: each joint's parent, axis
and placement, each geometry's shape (a convex hull from its hull's points; boxes,
spheres, cylinders and capsules as they are) and the pairs one request counts with their
margins. It asks coal each pair as Pinocchio does (so its answer is the Python check's),
after a bounding volume that contains each geometry has settled the pairs far apart, and
walks a whole path of :class:`~armfleet.planning.path_check.PathCertifier`'s proof in one
call, releasing the GIL.

The Python check stays as the reference: where the kernel is not built, for scenes whose
joints or shapes it does not know (a continuous joint, a static triangle mesh), and as the
independent check in the tests (``tests/test_planning_checks.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import coal
import numpy as np
import numpy.typing as npt
import pinocchio as pin

try:  # built by `pip install`; a source tree that was never built has none
    from armfleet.controllers._fleet_kernel import SceneCheck
except ImportError:  # pragma: no cover - the test command always builds it
    SceneCheck = None


def kernel_built() -> bool:
    """Whether the compiled check is there (the fleet kernel was built)."""
    return SceneCheck is not None


#: Pinocchio joints the compiled check rebuilds: revolute (0) or prismatic (1), and the axis.
JOINT_KINDS: dict[str, tuple[int, tuple[float, ...] | None]] = {
    "JointModelRX": (0, (1.0, 0.0, 0.0)),
    "JointModelRY": (0, (0.0, 1.0, 0.0)),
    "JointModelRZ": (0, (0.0, 0.0, 1.0)),
    "JointModelRevoluteUnaligned": (0, None),
    "JointModelPX": (1, (1.0, 0.0, 0.0)),
    "JointModelPY": (1, (0.0, 1.0, 0.0)),
    "JointModelPZ": (1, (0.0, 0.0, 1.0)),
    "JointModelPrismaticUnaligned": (1, None),
}
#: The compiled check's shape kinds.
BOX, SPHERE, CYLINDER, CAPSULE, CONVEX = range(5)
NO_POINTS = np.zeros((0, 3))


def placement_numbers(placement: pin.SE3) -> list[float]:
    """A placement as the compiled check takes it: rotation row by row, then translation."""
    return [*placement.rotation.ravel().tolist(), *placement.translation.tolist()]


def prismatic_travel(model: pin.Model, joint: int) -> float:
    """How far prismatic ``joint`` can move what it carries from its origin [m]: its
    largest limit (inf when it has none)."""
    index = model.joints[joint].idx_q
    limits = (model.lowerPositionLimit[index], model.upperPositionLimit[index])
    return float(max(abs(limits[0]), abs(limits[1])))


def shape_numbers(shape: coal.CollisionGeometry) -> tuple[int, list[float], Any] | None:
    """(kind, parameters, points) of a coal shape, or None for a shape the check lacks."""
    if isinstance(shape, coal.Box):
        return BOX, [float(x) for x in shape.halfSide], NO_POINTS
    if isinstance(shape, coal.Sphere):
        return SPHERE, [float(shape.radius)], NO_POINTS
    if isinstance(shape, coal.Cylinder):
        return CYLINDER, [float(shape.radius), float(shape.halfLength)], NO_POINTS
    if isinstance(shape, coal.Capsule):
        return CAPSULE, [float(shape.radius), float(shape.halfLength)], NO_POINTS
    if isinstance(shape, coal.ConvexBase) and shape.getSweptSphereRadius() == 0.0:
        return CONVEX, [], np.ascontiguousarray(np.asarray(shape.points(), dtype=float))
    return None


def compiled_scene_check(
    model: pin.Model,
    geometry: pin.GeometryModel,
    pairs: Sequence[tuple[int, int, float, float, float]],
    planned_columns: npt.NDArray[np.int_],
) -> Any | None:
    """The compiled check of a scene's ``model`` and ``geometry``, counting ``pairs``
    (first, second, margin, far margin, the physics margins within them), a state setting
    ``planned_columns`` of the configuration; None when the kernel is not built or does not
    know a joint or a shape."""
    if SceneCheck is None:
        return None
    parents, kinds, axes, placements, q_indices, travels = [], [], [], [], [], []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        known = JOINT_KINDS.get(joint.shortname())
        if known is None or joint.nq != 1:
            return None
        kind, axis = known
        if axis is None:
            axis = tuple(float(x) for x in joint.extract().axis)
        parents.append(int(model.parents[j]))
        kinds.append(kind)
        axes.append(axis)
        placements.append(placement_numbers(model.jointPlacements[j]))
        q_indices.append(int(joint.idx_q))
        travels.append(prismatic_travel(model, j) if kind == 1 else 0.0)
    if not all(np.isfinite(travels)):
        return None  # a prismatic joint without limits: no bound on how far it carries
    shapes = [shape_numbers(item.geometry) for item in geometry.geometryObjects]
    if any(shape is None for shape in shapes):
        return None
    check = SceneCheck(
        parents,
        kinds,
        np.array(axes, dtype=float).reshape(-1, 3),
        np.array(placements, dtype=float).reshape(-1, 12),
        q_indices,
        travels,
        model.nq,
    )
    for item, shape in zip(geometry.geometryObjects, shapes, strict=True):
        assert shape is not None
        kind, parameters, points = shape
        check.add_geometry(
            int(item.parentJoint), placement_numbers(item.placement), kind, parameters, points
        )
    first, second, margins, far_margins, grown = zip(*pairs, strict=True) if pairs else [()] * 5
    check.set_pairs(
        [int(a) for a in first],
        [int(b) for b in second],
        [float(m) for m in margins],
        [float(f) for f in far_margins],
        [float(g) for g in grown],
    )
    check.set_planned([int(c) for c in planned_columns])
    return check
