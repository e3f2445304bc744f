"""The final check of a path: every point between two checked states is proven clear.

A state that passes the checker keeps two bodies at least the clearance ``c`` apart
and two links of one arm at least their own margin ``m``. Between two such states
``Δq`` apart, no point of an arm moves further than ``d = Σ_i r_i |Δq_i|``, where
``r_i`` bounds the distance from joint i to any geometry it carries (the chain's joint
offsets plus the geometry's own extent). Take the nearer of the two states: from it, a
point has moved at most ``d / 2``. Two points of different arms have then closed in by
at most ``(d_a + d_b) / 2``, a point against a still body by ``d_a / 2``, and two points
of one arm by ``d_a / 2`` too (seen from the link nearer the base, only the joints
between them move the other). So when every step keeps ``d_a + d_b <= 2 c`` and
``d_a <= 2 m``, nothing can meet between checked states: the path is proven
contact-free, not sampled. The same holds with wider margins (the checker's ``far``
check) and proportionally longer steps, which is how most of a path is proven.

The pairs' margins hold the shapes' physics margins on top of ``c`` and ``m``
(:func:`~armfleet.planning.scene.physics_margin`), and the steps are sized with ``c`` and
``m`` alone: between checked states the scene's shapes stay that far apart, so PyBullet's
(grown by their margins) do not meet.

Where the checker has its compiled check, a whole path is walked in one compiled call
(``cpp/planning_check.cpp``: the same walk, the same steps); the reach bounds are made
once per scene and held objects' placements, not per request.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from armfleet.messages import FloatArray
from armfleet.planning.compiled_check import prismatic_travel
from armfleet.planning.scene import CollisionChecker


def joint_levers(checker: CollisionChecker) -> FloatArray:
    """Per planned joint (the checker's state order), a bound [m] on how far any
    geometry it carries is from it: how far a point moves per radian of that joint.

    Kept on the checker, and made again only when a held object sits elsewhere in its
    hand (the only geometry of the scene that moves on its joint)."""
    scene = checker.scene
    held = b"".join(
        scene.geometry.geometryObjects[index].placement.homogeneous.tobytes()
        for index in scene.object_geometries
        if scene.geometry.geometryObjects[index].parentJoint != 0
    )
    if checker.levers is not None and checker.levers[0] == held:
        return checker.levers[1]
    levers = _reach_bounds(checker)
    checker.levers = (held, levers)
    return levers


def _reach_bounds(checker: CollisionChecker) -> FloatArray:
    scene = checker.scene
    model = scene.model
    # A joint's offset from its parent, and what a prismatic joint adds to it (its travel).
    prismatic = [
        model.joints[j].shortname().startswith("JointModelP") for j in range(model.njoints)
    ]
    offsets = [
        float(np.linalg.norm(placement.translation))
        + (prismatic_travel(model, j) if prismatic[j] else 0.0)
        for j, placement in enumerate(model.jointPlacements)
    ]
    planned = scene.joint_ids(checker.arms)
    levers = np.zeros(len(planned))
    for item in scene.geometry.geometryObjects:
        if item.parentJoint == 0:
            continue
        shape = item.geometry
        shape.computeLocalAABB()
        extent = float(np.linalg.norm(item.placement.translation)) + float(
            np.linalg.norm(shape.aabb_center) + shape.aabb_radius
        )
        chain = list(model.supports[item.parentJoint])
        for k, joint in enumerate(planned):
            if joint in chain:
                after = chain[chain.index(joint) + 1 :]
                # A prismatic joint moves what it carries by its own motion, no more.
                reach = 1.0 if prismatic[joint] else extent + sum(offsets[j] for j in after)
                levers[k] = max(levers[k], reach)
    return levers


class PathCertifier:
    """Checks paths of one checker at the steps that prove them contact-free.

    Each segment is first walked in long steps with the wide margins of
    :meth:`CollisionChecker.far`; a step whose two ends are both far from everything is
    proven. Only the steps near something are walked again, in the short steps the
    clearance allows.

    Args:
        checker: the request's collision checker (its scene's margins must be > 0).
    """

    def __init__(self, checker: CollisionChecker) -> None:
        self._checker = checker
        scene = checker.scene
        if not (scene.clearance_m > 0.0 and scene.self_clearance_m > 0.0):
            raise ValueError("a contact-free proof needs margins > 0")
        self.levers = joint_levers(checker)
        self._near = (scene.clearance_m, scene.self_clearance_m)
        self._far = (scene.far_clearance_m, scene.far_self_clearance_m)
        sizes = [scene.columns(arm).size for arm in checker.arms]
        self._bounds = np.cumsum([0, *sizes])[:-1]
        if checker.compiled is not None:
            checker.compiled.set_proof(
                self.levers, [int(b) for b in self._bounds], *self._near, *self._far
            )

    def steps(self, start: FloatArray, end: FloatArray, far: bool = False) -> int:
        """Equal steps from ``start`` to ``end`` that keep the proof with the near (or far)
        margins (at least 1)."""
        between, within = self._far if far else self._near
        moved = self.levers * np.abs(end - start)
        per_arm = np.add.reduceat(moved, self._bounds)
        needed = max(float(per_arm.sum()) / (2.0 * between), float(per_arm.max()) / (2.0 * within))
        return max(1, math.ceil(needed))

    def first_failure(self, path: FloatArray) -> tuple[int, FloatArray] | None:
        """The first (segment index, state) of ``path`` that is not clear, or None.

        The waypoints themselves are checked too (the first one included). Each state is
        checked once: far first; a state that is not far is checked against the clearance
        (and fails the path if it is not clear), and so are the states inside a step with
        such an end.
        """
        checker = self._checker
        if checker.compiled is not None:
            found = checker.compiled.first_failure(np.ascontiguousarray(path, dtype=float))
            return None if found is None else (int(found[0]), np.asarray(found[1]))
        return walk(checker, path, lambda _, a, b, far: self.steps(a, b, far))


#: Equal steps that prove the motion from ``a`` to ``b`` on segment ``index`` of a path
#: (``steps(index, a, b, far)``), with the near (or far) margins.
Steps = Callable[[int, FloatArray, FloatArray, bool], int]


def walk(
    checker: CollisionChecker, path: FloatArray, steps: Steps
) -> tuple[int, FloatArray] | None:
    """The first (segment index, state) of ``path`` not clear, walked in ``steps``, or None.

    Each state is checked once: far first; a state that is not far is checked against the
    clearance (and fails the path if it is not clear), and so are the states inside a far
    step with such an end, in the clearance's steps."""
    far_before = checker.far(path[0])
    if not far_before and not checker.valid(path[0]):
        return 0, path[0]
    for index in range(len(path) - 1):
        start, end = path[index], path[index + 1]
        count = steps(index, start, end, True)
        grid = start + np.linspace(0.0, 1.0, count + 1)[:, None] * (end - start)
        for k in range(count):
            a, b = grid[k], grid[k + 1]
            far_after = checker.far(b)
            if not far_after and not checker.valid(b):
                return index, b
            if not (far_before and far_after):  # near something: the clearance's steps
                fine = steps(index, a, b, False)
                for s in np.arange(1, fine) / fine:
                    state = a + s * (b - a)
                    if not checker.valid(state):
                        return index, state
            far_before = far_after
    return None
