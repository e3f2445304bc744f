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
contact-free, not sampled.
"""

from __future__ import annotations

import math

import numpy as np

from armfleet.messages import FloatArray
from armfleet.planning.scene import CollisionChecker


def joint_levers(checker: CollisionChecker) -> FloatArray:
    """Per planned joint (the checker's state order), a bound [m] on how far any
    geometry it carries is from it: how far a point moves per radian of that joint."""
    scene = checker.scene
    model = scene.model
    offsets = [float(np.linalg.norm(p.translation)) for p in model.jointPlacements]
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
                reach = extent + sum(offsets[j] for j in after)
                levers[k] = max(levers[k], reach)
    return levers


class PathCertifier:
    """Checks paths of one checker at the step that proves them contact-free.

    Args:
        checker: the request's collision checker (its scene's margins must be > 0).
    """

    def __init__(self, checker: CollisionChecker) -> None:
        self._checker = checker
        scene = checker.scene
        if not (scene.clearance_m > 0.0 and scene.self_clearance_m > 0.0):
            raise ValueError("a contact-free proof needs margins > 0")
        self.levers = joint_levers(checker)
        self._clearance_m = scene.clearance_m
        self._self_clearance_m = scene.self_clearance_m
        #: Per planned arm, its joints' positions in a state.
        sizes = [scene.columns(arm).size for arm in checker.arms]
        self._bounds = np.cumsum([0, *sizes])

    def steps(self, start: FloatArray, end: FloatArray) -> int:
        """Equal steps from ``start`` to ``end`` that keep the proof (at least 1)."""
        moved = self.levers * np.abs(end - start)
        per_arm = np.add.reduceat(moved, self._bounds[:-1])
        needed = max(
            float(per_arm.sum()) / (2.0 * self._clearance_m),
            float(per_arm.max()) / (2.0 * self._self_clearance_m),
        )
        return max(1, math.ceil(needed))

    def first_failure(self, path: FloatArray) -> tuple[int, FloatArray] | None:
        """The first (segment index, state) of ``path`` that is not clear, or None.

        The waypoints themselves are checked too (the first one included)."""
        if not self._checker.valid(path[0]):
            return 0, path[0]
        for index in range(len(path) - 1):
            start, end = path[index], path[index + 1]
            steps = self.steps(start, end)
            for s in np.arange(1, steps + 1) / steps:
                state = start + s * (end - start)
                if not self._checker.valid(state):
                    return index, state
        return None

    def clear(self, start: FloatArray, end: FloatArray) -> bool:
        """Whether the straight line ``start`` -> ``end`` is proven contact-free."""
        return self.first_failure(np.array([start, end])) is None
