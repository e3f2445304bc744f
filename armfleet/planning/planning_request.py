"""A planning request as read from the world, ready to be planned on any thread.

:meth:`~armfleet.planning.motion_planner.MotionPlanner.prepare` reads the world on the
stepping thread (cheap: where everything is, the arms' starts and limits, the moving arms'
remaining references, the pose goals' frames) into a :class:`PlanningRequest`; from then
on the request is plain data and planning it (IK, search, proof, timing,
:meth:`~armfleet.planning.motion_planner.MotionPlanner.solve`) reads nothing of the
world, so it may run on a worker thread while the world goes on stepping.

A pose goal becomes a :data:`PoseSolver`: its frame is looked up when the request is read,
and the IK it then runs has its own Pinocchio data, from the arm's position at that step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from armfleet.errors import ArmfleetError, UnreachablePose
from armfleet.kinematics.continuous_joints import nearest_turn
from armfleet.messages import FloatArray
from armfleet.motion.move_options import PlanningLimit
from armfleet.planning.failure import FailureReason, PlanningFailed
from armfleet.planning.moving_arms import MovingArm
from armfleet.planning.path_timing import JointLimits
from armfleet.planning.problem import search_bounds
from armfleet.planning.scene import CollisionChecker
from armfleet.planning.scene_pool import SceneSnapshot

#: Rounds of other IK solutions (one per pose-goal arm, in turn) tried for a goal whose
#: first solution is in collision.
IK_ALTERNATIVES = 12

#: IK of one pose goal, safe on any thread: the arm joints for a seed (None: from where
#: the arm was when the request was read), or :class:`~armfleet.errors.UnreachablePose`.
PoseSolver = Callable[[FloatArray | None], FloatArray]


@dataclass(frozen=True)
class ArmRequest:
    """One arm of a request, as it was when the request was read.

    Attributes:
        name: arm name.
        joint_names: its controlled joints (the columns of its part of a state).
        start: where its reference rests [rad or m].
        goal: its joint goal (checked against its limits), or None for a pose goal.
        solve_pose: the IK of its pose goal, or None for a joint goal.
        lower, upper: its joint position limits (infinite for a continuous joint).
        continuous: per joint, whether it is continuous.
        period: its controller's period [s] (its motion is sampled at it).
        limits: its velocity, acceleration and jerk limits.
    """

    name: str
    joint_names: tuple[str, ...]
    start: FloatArray
    goal: FloatArray | None
    solve_pose: PoseSolver | None
    lower: FloatArray
    upper: FloatArray
    continuous: npt.NDArray[np.bool_]
    period: float
    limits: JointLimits


@dataclass(frozen=True)
class PlanningRequest:
    """Everything a plan is made from, read from the world at one step.

    Attributes:
        arms: the planned arms, in the order of a state.
        scene: the world at that step.
        movers: the arms outside the request that were moving, and their remaining motion.
        clearance_m: margin kept between different bodies [m].
        limit: the request's time or iteration budget.
        stamp: the world's simulated time at that step [s].
        read_s: wall time spent reading the world (on the stepping thread) [s].
        seconds: wall time per phase so far [s].
    """

    arms: tuple[ArmRequest, ...]
    scene: SceneSnapshot
    movers: tuple[MovingArm, ...]
    clearance_m: float
    limit: PlanningLimit
    stamp: float
    read_s: float
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(arm.name for arm in self.arms)

    @property
    def start(self) -> FloatArray:
        return np.concatenate([arm.start for arm in self.arms])

    @property
    def continuous(self) -> npt.NDArray[np.bool_]:
        return np.concatenate([arm.continuous for arm in self.arms])

    def bounds(self, goal: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The box the search samples, from the start to ``goal``
        (:func:`~armfleet.planning.problem.search_bounds`)."""
        return search_bounds(
            np.concatenate([arm.lower for arm in self.arms]),
            np.concatenate([arm.upper for arm in self.arms]),
            self.continuous,
            self.start,
            goal,
        )

    def limits(self) -> JointLimits:
        """Every planned joint's velocity, acceleration and jerk limits, in state order."""
        parts = [arm.limits for arm in self.arms]
        return JointLimits(
            np.concatenate([p.velocity for p in parts]),
            np.concatenate([p.acceleration for p in parts]),
            np.concatenate([p.jerk for p in parts]),
        )


def goal_state(request: PlanningRequest, checker: CollisionChecker) -> FloatArray:
    """The goal state: joint goals as given, pose goals by IK, preferring a solution clear
    of collisions when the nearest one is not; a continuous joint's angle the equivalent
    nearest its start.

    Raises:
        PlanningFailed: a pose goal IK cannot reach (``goal unreachable``).
    """
    start, continuous = request.start, request.continuous
    offsets = np.cumsum([0, *(len(arm.joint_names) for arm in request.arms)])
    parts: list[FloatArray] = []
    pose_goals: dict[int, ArmRequest] = {}
    for index, arm in enumerate(request.arms):
        if arm.solve_pose is None:
            assert arm.goal is not None  # an arm's goal is joints or a pose
            parts.append(arm.goal)
        else:
            parts.append(_solve(arm, None))
            pose_goals[index] = arm
    state = nearest_turn(np.concatenate(parts), start, continuous)
    if not pose_goals or checker.valid(state):
        return state
    generator = np.random.default_rng(0)
    for _ in range(IK_ALTERNATIVES):
        for index, arm in pose_goals.items():  # one arm at a time: the others keep
            here = start[offsets[index] : offsets[index + 1]]  # what they have found
            low, high = search_bounds(arm.lower, arm.upper, arm.continuous, here, here)
            try:
                parts[index] = _solve(arm, generator.uniform(low, high))
            except ArmfleetError:
                continue
            candidate = nearest_turn(np.concatenate(parts), start, continuous)
            if checker.valid(candidate):
                return candidate
    return state  # the nearest solution; the search names what it touches


def _solve(arm: ArmRequest, seed: FloatArray | None) -> FloatArray:
    assert arm.solve_pose is not None
    try:
        return arm.solve_pose(seed)
    except UnreachablePose as exc:
        raise PlanningFailed(FailureReason.GOAL_UNREACHABLE, str(exc), arms=(arm.name,)) from exc


def arm_limits(velocity: FloatArray, acceleration: float, jerk: float) -> JointLimits:
    """An arm's limits: per joint velocity, and one acceleration and jerk for every joint."""
    size = velocity.size
    return JointLimits(
        np.asarray(velocity, dtype=float), np.full(size, acceleration), np.full(size, jerk)
    )
