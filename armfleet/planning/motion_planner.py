"""Plans for the arms of one world, from the world as it is, and runs the plans.

Each request takes a snapshot of the world (:class:`PlanningScene`, rebuilt only when
arms, objects or what the grippers hold change; otherwise only moved), turns its goals
into a :class:`PlanningProblem`, finds a proven-clear path, times it, checks it in time
against the arms that are moving, and returns a :class:`Plan`. Nothing moves until
:meth:`MotionPlanner.execute`.

A continuous joint's goal is the equivalent of the asked angle nearest its start (a planned
move takes the short way round: from 3.0 rad, a goal of -3.0 rad ends at 2 pi - 3.0), and it
is searched over a window of a turn and more (:func:`~armfleet.planning.problem.search_bounds`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from armfleet.checks.number_ranges import CLEARANCE_M, PLANNING_TIMEOUT_S
from armfleet.controllers.gripper_joints import finger_indices
from armfleet.controllers.jerk_limited_trajectory import SampledMotion
from armfleet.errors import (
    ArmFault,
    ArmfleetError,
    ArmInMotion,
    ProtectiveStopError,
    UnknownArm,
    UnreachablePose,
)
from armfleet.kinematics.continuous_joints import nearest_turn
from armfleet.messages import FloatArray, PlannedMotion
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, DEFAULT_TIMEOUT_S
from armfleet.motion.pose_goal import PoseGoal
from armfleet.planning.failure import FailureReason, PlanningFailed
from armfleet.planning.moving_arms import MovingArm, find_start_delay
from armfleet.planning.object_geometry import object_placement, object_shape
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.path_search import find_path
from armfleet.planning.path_timing import JointLimits, TimedPath
from armfleet.planning.plan import Plan
from armfleet.planning.planned_arm import PlannedArm
from armfleet.planning.problem import PlanningProblem, search_bounds
from armfleet.planning.scene import ArmGeometry, PlanningScene, SceneObject, arm_geometry

if TYPE_CHECKING:
    from armfleet.objects import WorldObject

#: Rounds of other IK solutions (one per pose-goal arm, in turn) tried for a goal whose
#: first solution is in collision.
IK_ALTERNATIVES = 12
#: Tool path points drawn per second of motion.
TOOL_PATH_RATE_HZ = 50.0


Goal = Any  # joint positions, or a PoseGoal


class MotionPlanner:
    """Collision-free planning for the arms of one world.

    Args:
        arms: the world's arms by name, now.
        objects: the world's objects by name, now.
        touching: the bodies an arm touched at the last step.
        now: the world's simulated time [s].
    """

    def __init__(
        self,
        arms: Callable[[], Mapping[str, PlannedArm]],
        objects: Callable[[], Mapping[str, WorldObject]],
        touching: Callable[[str], set[str]],
        now: Callable[[], float],
    ) -> None:
        self._arms = arms
        self._objects = objects
        self._touching = touching
        self._now = now
        self._geometries: dict[str, tuple[PlannedArm, ArmGeometry]] = {}
        self._scene: tuple[tuple[Any, ...], PlanningScene] | None = None

    # -- planning ------------------------------------------------------------------------
    def plan(
        self,
        goals: Mapping[str, Goal],
        *,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float = DEFAULT_TIMEOUT_S,
    ) -> Plan:
        """Plan ``goals`` (per arm name: joint positions or a :class:`PoseGoal`) jointly.

        Raises:
            PlanningFailed: start or goal in collision, goal unreachable, or no path.
            UnknownArm, ArmInMotion, ArmFault, ProtectiveStopError, and the errors of
                ``arm.move_to`` / ``arm.solve_ik`` for bad goals. Nothing moves.
        """
        began = time.perf_counter()
        clearance_m = CLEARANCE_M.check(clearance_m, "clearance_m")
        timeout_s = PLANNING_TIMEOUT_S.check(timeout_s, "timeout_s")
        if not isinstance(goals, Mapping) or not goals:
            raise ArmfleetError("plan takes a mapping {arm name: goal} with at least one arm")
        world_arms = self._arms()
        arms = [self._ready_arm(world_arms, name) for name in goals]
        names = tuple(arm.name for arm in arms)
        seconds: dict[str, float] = {}
        mark = time.perf_counter()
        scene = self._snapshot(clearance_m)
        movers = self._moving_arms(world_arms, names)
        for mover in movers:
            scene.set_arm_controlled(mover.name, mover.final)
        seconds["scene"] = time.perf_counter() - mark
        checker = scene.checker(names)
        start = np.concatenate([self._start(arm) for arm in arms])
        mark = time.perf_counter()
        goal = self._goal_state(arms, goals, start, checker)
        seconds["ik"] = time.perf_counter() - mark
        lower, upper = search_bounds(
            np.concatenate([arm.position_controller.lower for arm in arms]),
            np.concatenate([arm.position_controller.upper for arm in arms]),
            np.concatenate([_continuous(arm) for arm in arms]),
            start,
            goal,
        )
        problem = PlanningProblem(names, start, goal, lower, upper, checker, timeout_s)
        path = find_path(problem, deadline=began + timeout_s)
        seconds.update(path.seconds)
        mark = time.perf_counter()
        timed = TimedPath(path.waypoints, _limits(arms))
        seconds["timing"] = time.perf_counter() - mark
        mark = time.perf_counter()
        delay, conflict = find_start_delay(scene, names, timed, movers)
        seconds["in_time"] = time.perf_counter() - mark
        if conflict is not None:
            raise PlanningFailed(
                FailureReason.NO_PATH,
                f"{conflict.arm} is moving through the path ({conflict.time_s:.2f} s in) "
                "and waiting for it does not clear it; plan again once it has stopped",
                arms=names,
                blocking_arm=conflict.arm,
                problem=problem,
            )
        return Plan(
            arms=names,
            joint_names={arm.name: arm.joint_names for arm in arms},
            waypoints=path.waypoints,
            duration_s=delay + timed.duration,
            start_delay_s=delay,
            planning_time_s=time.perf_counter() - began,
            collision_checks=checker.checks,
            samples=path.samples,
            clearance_m=clearance_m,
            stamp=self._now(),
            timing=timed,
            seconds=seconds,
        )

    def _ready_arm(self, world_arms: Mapping[str, PlannedArm], name: Any) -> PlannedArm:
        if not isinstance(name, str) or name not in world_arms:
            raise UnknownArm(name, list(world_arms))
        arm = world_arms[name]
        fault = arm.controller_manager.fault
        if fault is not None:
            raise ArmFault(name, fault)
        controller = arm.position_controller
        if controller.stop_reason is not None:
            raise ProtectiveStopError(name, controller.stop_reason)
        if controller.is_moving or controller.trajectory is None:
            raise ArmInMotion(name, "a planned move")
        return arm

    @staticmethod
    def _start(arm: PlannedArm) -> FloatArray:
        trajectory = arm.position_controller.trajectory
        assert trajectory is not None  # _ready_arm checked it
        return np.array(trajectory.position, dtype=float)

    def _goal_state(
        self, arms: list[PlannedArm], goals: Mapping[str, Goal], start: FloatArray, checker: Any
    ) -> FloatArray:
        """The goal state: joint goals as given, pose goals by IK, preferring a solution
        clear of collisions when the nearest one is not; a continuous joint's angle the
        equivalent nearest its start."""
        continuous = np.concatenate([_continuous(arm) for arm in arms])
        offsets = np.cumsum([0, *(len(arm.joint_names) for arm in arms)])
        parts: list[FloatArray] = []
        pose_goals: dict[int, tuple[PlannedArm, PoseGoal]] = {}
        for index, arm in enumerate(arms):
            goal = goals[arm.name]
            if isinstance(goal, PoseGoal):
                parts.append(_solve_pose(arm, goal, None))
                pose_goals[index] = (arm, goal)
            else:
                parts.append(arm.position_controller.validate(goal))
        state = nearest_turn(np.concatenate(parts), start, continuous)
        if not pose_goals or checker.valid(state):
            return state
        generator = np.random.default_rng(0)
        for _ in range(IK_ALTERNATIVES):
            for index, (arm, goal) in pose_goals.items():  # one arm at a time: the others
                here = start[offsets[index] : offsets[index + 1]]  # keep what they have found
                low, high = search_bounds(*arm.joint_limits, _continuous(arm), here, here)
                try:
                    parts[index] = _solve_pose(arm, goal, generator.uniform(low, high))
                except ArmfleetError:
                    continue
                candidate = nearest_turn(np.concatenate(parts), start, continuous)
                if checker.valid(candidate):
                    return candidate
        return state  # the nearest solution; the search names what it touches

    # -- the scene -----------------------------------------------------------------------------
    def _snapshot(self, clearance_m: float) -> PlanningScene:
        """The world now, as a planning scene (rebuilt only when its parts changed)."""
        arms = self._arms()
        objects = self._objects()
        held = self._held_objects(arms, objects)
        key = (
            clearance_m,
            tuple((name, id(arm)) for name, arm in arms.items()),
            tuple((name, id(obj)) for name, obj in objects.items()),
            tuple(sorted(held.items())),
        )
        if self._scene is None or self._scene[0] != key:
            geometries = [self._geometry(arm) for arm in arms.values()]
            parts = [
                SceneObject(name, object_shape(obj), pin.SE3.Identity(), held.get(name))
                for name, obj in objects.items()
            ]
            self._scene = (key, PlanningScene(geometries, parts, clearance_m))
        scene = self._scene[1]
        for name, arm in arms.items():
            scene.set_arm(name, arm.body.position)
        for name, obj in objects.items():
            holder = held.get(name)
            if holder is None:
                scene.set_object(name, object_placement(obj))
            else:
                scene.set_object(name, _in_hand(arms[holder], obj, scene))
        return scene

    def _geometry(self, arm: PlannedArm) -> ArmGeometry:
        cached = self._geometries.get(arm.name)
        if cached is not None and cached[0] is arm:
            return cached[1]
        kinematics = arm.kinematics
        named = arm.description.gripper_joints
        fingers = [kinematics.joint_names[i] for i in finger_indices(kinematics, named)]
        geometry = arm_geometry(
            arm.name,
            arm.description.urdf,
            kinematics.model,
            arm.joint_names,
            arm.description.ignored_contacts,
            fingers,
        )
        self._geometries[arm.name] = (arm, geometry)
        return geometry

    def _held_objects(
        self, arms: Mapping[str, PlannedArm], objects: Mapping[str, WorldObject]
    ) -> dict[str, str]:
        """Object name -> the arm whose gripper holds it (squeezing, touching it)."""
        held: dict[str, str] = {}
        for name, arm in arms.items():
            if not arm.has_gripper or not arm.gripper.holding:
                continue
            for touched in self._touching(name):
                obj = objects.get(touched)
                if obj is not None and not obj.is_static:
                    held[touched] = name
        return held

    def _moving_arms(
        self, arms: Mapping[str, PlannedArm], planned: tuple[str, ...]
    ) -> list[MovingArm]:
        movers = []
        for name, arm in arms.items():
            controller = arm.position_controller
            if name in planned or not controller.is_moving or controller.trajectory is None:
                continue
            rows = controller.trajectory.remaining_positions(controller.period)
            if len(rows):
                movers.append(MovingArm(name, rows, controller.period))
        return movers

    # -- execution ------------------------------------------------------------------------------
    def execute(self, plan: Plan) -> float:
        """Start ``plan`` on its arms, all on this step; returns its duration [s].

        A plan made at an earlier step is checked again against the world as it is
        now (and its start against where the arms are).

        Raises:
            ArmfleetError: the plan is no longer valid (say why); nothing moves.
        """
        if not isinstance(plan, Plan):
            raise ArmfleetError(
                f"execute takes a Plan from world.plan(), got {type(plan).__name__}"
            )
        world_arms = self._arms()
        arms = [self._ready_arm(world_arms, name) for name in plan.arms]
        start = np.concatenate([self._start(arm) for arm in arms])
        if not np.allclose(start, plan.waypoints[0], atol=1e-6, rtol=0.0):
            raise ArmfleetError(
                f"the plan of {' + '.join(plan.arms)} starts elsewhere than the arms are now: "
                "plan again from here"
            )
        delay = plan.start_delay_s
        if self._now() != plan.stamp:
            delay = self._recheck(plan)
        motions = {}
        for arm in arms:
            controller = arm.position_controller
            motion = plan.timing.sample(controller.period)
            columns = plan.columns(arm.name)
            own = _delayed(
                motion, columns, plan.waypoints[0, columns], round(delay / controller.period)
            )
            controller.check_samples(own)
            motions[arm.name] = own
        stamp = self._now()
        for arm in arms:
            own = motions[arm.name]
            arm.publish_planned(_announcement(arm, plan, own, stamp))
            arm.follow_motion(own)
        return delay + plan.timing.duration

    def _recheck(self, plan: Plan) -> float:
        """The start delay a plan made earlier needs now; raise if it no longer holds."""
        scene = self._snapshot(plan.clearance_m)
        movers = self._moving_arms(self._arms(), plan.arms)
        for mover in movers:
            scene.set_arm_controlled(mover.name, mover.final)
        checker = scene.checker(plan.arms)
        failure = PathCertifier(checker).first_failure(plan.waypoints)
        if failure is not None:
            found = checker.collision(failure[1])
            what = f" ({found[0]} / {found[1]})" if found else ""
            raise ArmfleetError(
                f"the plan of {' + '.join(plan.arms)} is no longer clear: the world changed "
                f"since it was planned{what}; plan again"
            )
        delay, conflict = find_start_delay(scene, plan.arms, plan.timing, movers)
        if conflict is not None:
            raise ArmfleetError(
                f"the plan of {' + '.join(plan.arms)} is no longer clear: {conflict.arm} is "
                "moving through it; plan again"
            )
        return delay


def _solve_pose(arm: PlannedArm, goal: PoseGoal, seed: FloatArray | None) -> FloatArray:
    try:
        return arm.solve_ik(goal.pose, goal.frame, link=goal.link, seed=seed)
    except UnreachablePose as exc:
        raise PlanningFailed(FailureReason.GOAL_UNREACHABLE, str(exc), arms=(arm.name,)) from exc


def _continuous(arm: PlannedArm) -> npt.NDArray[np.bool_]:
    """Per joint of ``arm.joint_names``: whether it is continuous (no position limit)."""
    kinematics = arm.kinematics
    mask: npt.NDArray[np.bool_] = kinematics.continuous[kinematics.arm_indices]
    return mask


def _limits(arms: list[PlannedArm]) -> JointLimits:
    velocity, acceleration, jerk = [], [], []
    for arm in arms:
        controller = arm.position_controller
        n = controller.lower.size
        velocity.append(controller.max_velocity)
        acceleration.append(np.full(n, float(controller.parameters["max_acceleration_rad_s2"])))
        jerk.append(np.full(n, float(controller.parameters["max_jerk_rad_s3"])))
    return JointLimits(np.concatenate(velocity), np.concatenate(acceleration), np.concatenate(jerk))


def _in_hand(arm: PlannedArm, obj: WorldObject, scene: PlanningScene) -> pin.SE3:
    """Where a held object is in the frame of the hand joint that holds it."""
    hand = scene.hand_joint(arm.name)
    kinematics = arm.kinematics
    data = kinematics.model.createData()
    pin.forwardKinematics(kinematics.model, data, arm.body.position)
    hand_pose = data.oMi[kinematics.model.getJointId(hand)]
    return hand_pose.actInv(object_placement(obj))


def _delayed(motion: SampledMotion, columns: slice, start: FloatArray, rows: int) -> SampledMotion:
    """``motion``'s ``columns``, after ``rows`` periods held at ``start``."""
    position = motion.position[:, columns]
    velocity = motion.velocity[:, columns]
    acceleration = motion.acceleration[:, columns]
    if rows > 0:
        hold = np.repeat(start[None, :], rows, axis=0)
        zeros = np.zeros_like(hold)
        position = np.vstack([hold, position])
        velocity = np.vstack([zeros, velocity])
        acceleration = np.vstack([zeros, acceleration])
    return SampledMotion(
        np.ascontiguousarray(position),
        np.ascontiguousarray(velocity),
        np.ascontiguousarray(acceleration),
    )


def _announcement(
    arm: PlannedArm, plan: Plan, motion: SampledMotion, stamp: float
) -> PlannedMotion:
    columns = plan.columns(arm.name)
    period = arm.position_controller.period
    every = max(1, round(1.0 / (TOOL_PATH_RATE_HZ * period)))
    rows = motion.position[::every]
    if len(motion.position) and (len(motion.position) - 1) % every:
        rows = np.vstack([rows, motion.position[-1:]])
    tool_path = (
        np.array([arm.tool_position(row) for row in rows]) if len(rows) else np.empty((0, 3))
    )
    delay = plan.start_delay_s
    times = tuple(float(delay + t) for t in plan.timing.times)
    return PlannedMotion(stamp, arm.joint_names, times, plan.waypoints[:, columns], tool_path)
