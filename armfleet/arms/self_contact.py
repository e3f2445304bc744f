"""Would a straight motion of one arm touch the arm itself? Asked before it starts.

A world refuses an arm that would touch itself at its spawn configuration
(:mod:`armfleet.physics.start_clearance`); this holds a motion to the same rule, so
that a target the arm cannot reach without touching itself is refused before anything
moves (:class:`~armfleet.errors.SelfContactError`, naming the two links), instead of
ending in a protective stop on the way (a Panda sent to its lower joint limits stopped
with link1 in link5, 0.66 rad short).

What is checked is the motion the arm will follow: the jerk-limited reference from
where the reference is now to the target (Ruckig's, time-synchronised, which bends up to
0.4 rad away from the straight joint-space line on a long Panda motion), or a Cartesian
line's samples. The curve is *proven* clear, not sampled: it is cut into knots and
walked with the planner's proof (:class:`~armfleet.planning.curve_check.CurveCertifier`,
its deviation from the chords bounded by the controller's acceleration and jerk limits),
on a planning scene holding this arm alone. Measured on a Panda: 0.3 ms for a 0.3 s
motion, 1-10 ms for a 2 s one; the scene is built on the first move (~30 ms).

The rule is spawn's: two links of one arm count when neither is one rigid piece with the
other nor one joint apart and the pair is not among the description's
``ignored_contacts``; they touch when closer than
:data:`~armfleet.physics.start_clearance.CLEARANCE_M` (1 mm), PyBullet's collision margins
of their shapes included (:func:`~armfleet.planning.scene.physics_margin`). Only the arm
itself counts: other arms move and objects come and go (a collision-free motion around
them is ``avoid_collisions=True``), and the floor is not this rule's (the arm is lifted
far above it in its scene).

A motion that starts touching itself (after a protective stop) may move out: the knots
at its start that are not clear are passed over, and from the first clear one on, the
curve and the target must be.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import ruckig

from armfleet.controllers.gripper_joints import finger_indices
from armfleet.controllers.jerk_limited_trajectory import MotionPlan, SampledMotion, calculate
from armfleet.controllers.position_controller import PositionController
from armfleet.description import ArmDescription
from armfleet.errors import SelfContactError
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray
from armfleet.physics.start_clearance import CLEARANCE_M
from armfleet.planning.curve_check import CurveCertifier
from armfleet.planning.scene import CollisionChecker, PlanningScene, TooClose, arm_geometry

#: How far the arm is lifted above the planning scene's floor [m]: out of any arm's reach.
LIFT_M = 1000.0


class SelfContactCheck:
    """Checks one arm's motions against touching itself (built on first use).

    Args:
        name: the arm's name.
        description: its expanded model (URDF, ignored contact pairs, gripper joints).
        kinematics: its Pinocchio model; ``positions`` below are its movable joints.
        controller: its position controller (the joints it moves, its limits).
    """

    #: Left as they are by a world snapshot's restore (armfleet.world.object_state): the
    #: scene is built from the arm's model alone, and set to the arm's joints at each use.
    snapshot_caches = frozenset({"_scene"})

    def __init__(
        self,
        name: str,
        description: ArmDescription,
        kinematics: ArmKinematics,
        controller: PositionController,
    ) -> None:
        self._name = name
        self._description = description
        self._kinematics = kinematics
        self._controller = controller
        self._scene: PlanningScene | None = None

    def check_plan(self, plan: MotionPlan, positions: FloatArray) -> None:
        """Raise if the motion of ``plan`` (made by the position controller from its
        reference) would bring the arm within the clearance of itself.

        Args:
            plan: the motion.
            positions: every movable joint now [rad or m] (the fingers stay there).

        Raises:
            SelfContactError: at the target, or on the way; naming the two links.
        """
        checker, certifier = self._ready(positions)
        knots, accelerations, period = plan_knots(plan, certifier.knot_period)
        self._check(checker, certifier, knots, accelerations, period)

    def check_samples(
        self, start: FloatArray, motion: SampledMotion, period: float, positions: FloatArray
    ) -> None:
        """Raise if the sampled ``motion`` (one row per ``period`` [s] after ``start``, the
        arm joints) would bring the arm within the clearance of itself.

        Raises:
            SelfContactError: at its end, or on the way; naming the two links.
        """
        checker, certifier = self._ready(positions)
        stride = max(1, math.floor(certifier.knot_period / period))
        rows = np.arange(stride - 1, motion.steps, stride)
        if rows.size == 0 or rows[-1] != motion.steps - 1:
            rows = np.append(rows, motion.steps - 1)
        knots = np.vstack([start, motion.position[rows]])
        # Knots ``stride`` periods apart (the last may be nearer); a line's samples keep the
        # acceleration limit, not a jerk limit: the chords' deviation is bounded by the former.
        self._check(checker, certifier, knots, None, stride * period)

    def _ready(self, positions: FloatArray) -> tuple[CollisionChecker, CurveCertifier]:
        """The checker with the arm's other joints (fingers) at ``positions``."""
        if self._scene is None:
            self._scene = self._build_scene()
        self._scene.set_arm(self._name, positions)
        checker = self._scene.checker([self._name])
        # The controller's limits now bound the curve's bend (the reach bounds are kept on
        # the checker: a certifier costs microseconds).
        controller = self._controller
        size = len(controller.joint_names)
        certifier = CurveCertifier(
            checker,
            np.full(size, float(controller.parameters["max_acceleration_rad_s2"])),
            np.full(size, float(controller.parameters["max_jerk_rad_s3"])),
        )
        return checker, certifier

    def _build_scene(self) -> PlanningScene:
        kinematics = self._kinematics
        named = self._description.gripper_joints
        fingers = [kinematics.joint_names[i] for i in finger_indices(kinematics, named)]
        geometry = arm_geometry(
            self._name,
            self._description.urdf,
            lifted(kinematics.model, LIFT_M),
            self._controller.joint_names,
            self._description.ignored_contacts,
            fingers,
        )
        return PlanningScene([geometry], [], CLEARANCE_M)

    def _check(
        self,
        checker: CollisionChecker,
        certifier: CurveCertifier,
        knots: FloatArray,
        accelerations: FloatArray | None,
        period: float,
    ) -> None:
        target = knots[-1]
        if not checker.valid(target):
            raise self._refusal(checker, target, at_target=True)
        first = 0
        while first < len(knots) - 1 and not checker.valid(knots[first]):
            first += 1  # touching itself where it starts: it may move out
        rest = None if accelerations is None else accelerations[first:]
        found = certifier.first_failure(knots[first:], period, rest)
        if found is not None:
            raise self._refusal(checker, found[1], at_target=False)

    def _refusal(
        self, checker: CollisionChecker, state: FloatArray, *, at_target: bool
    ) -> SelfContactError:
        closest = closest_pair(checker, state)
        grown = closest.margin_m - checker.scene.self_clearance_m  # the physics' margins
        return SelfContactError(
            self._name,
            closest.first,
            closest.second,
            closest.distance_m - grown,
            checker.scene.self_clearance_m,
            at_target,
        )


def plan_knots(plan: MotionPlan, knot_period: float) -> tuple[FloatArray, FloatArray, float]:
    """Knots of ``plan``'s reference at most ``knot_period`` [s] apart, its start and its
    target included: (positions, accelerations, their spacing [s])."""
    dofs = len(plan.position_min)
    trajectory = ruckig.Trajectory(dofs)
    calculate(ruckig.Ruckig(dofs), plan.input, trajectory)
    duration = float(trajectory.duration)
    count = max(1, math.ceil(duration / knot_period))
    samples = [trajectory.at_time(duration * k / count) for k in range(count + 1)]
    positions = np.array([sample[0] for sample in samples], dtype=float)
    accelerations = np.array([sample[2] for sample in samples], dtype=float)
    positions[-1] = plan.input.target_position  # exactly where the reference ends
    return positions, accelerations, duration / count


def lifted(model: pin.Model, height_m: float) -> pin.Model:
    """A copy of ``model`` with everything it places in the world raised by ``height_m``.

    A joint frame named as a link (a Unitree Z1's ``gripperStator``) is renamed
    ``<name>__joint``: the scene appends the model by frame names, and only the links'
    frames carry geometry."""
    lift = pin.SE3(np.eye(3), np.array([0.0, 0.0, height_m]))
    raised = model.copy()
    for joint in range(1, raised.njoints):
        if raised.parents[joint] == 0:
            raised.jointPlacements[joint] = lift * raised.jointPlacements[joint]
    links = {frame.name for frame in raised.frames if frame.type == pin.FrameType.BODY}
    for index, frame in enumerate(raised.frames):
        if index == 0:  # the universe itself
            continue
        changed = raised.frames[index]
        if frame.parentJoint == 0:
            changed.placement = lift * changed.placement
        if frame.type != pin.FrameType.BODY and frame.name in links:
            changed.name = f"{frame.name}__joint"
        raised.frames[index] = changed
    return raised


def closest_pair(checker: CollisionChecker, state: FloatArray) -> TooClose:
    """The pair of the checker's active pairs nearest to touching at ``state`` (margins
    counted: the smallest distance less margin), for messages."""
    scene = checker.scene
    q = scene.positions.copy()
    q[checker.columns] = state
    pin.updateGeometryPlacements(scene.model, scene.model.createData(), scene.geometry,
                                 checker.data, q)  # fmt: skip
    best: TooClose | None = None
    for index in np.flatnonzero(checker.active):
        pair = scene.geometry.collisionPairs[int(index)]
        distance = float(pin.computeDistance(scene.geometry, checker.data, int(index)).min_distance)
        margin = float(scene.margins[int(index)])
        if best is None or distance - margin < best.distance_m - best.margin_m:
            best = TooClose(scene.body_link(pair.first), scene.body_link(pair.second),
                            distance, margin)  # fmt: skip
    assert best is not None  # an arm with no pair to check never fails a check
    return best
