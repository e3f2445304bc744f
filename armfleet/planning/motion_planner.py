"""Plans for the arms of one world, from the world as it is, and runs the plans.

A request is made in two parts, so that the world need not wait for it:

- :meth:`MotionPlanner.prepare` reads the world, on the thread that steps it, into a
  :class:`~armfleet.planning.planning_request.PlanningRequest` (where everything is, the
  arms' starts and limits, the moving arms' remaining motions; cheap);
- :meth:`MotionPlanner.solve` plans it on any thread, reading nothing of the world: it
  takes a :class:`PlanningScene` of the world's make from a
  :class:`~armfleet.planning.scene_pool.ScenePool` (rebuilt only when arms, objects or
  what the grippers hold change; otherwise only moved), turns the goals into a
  :class:`PlanningProblem`, finds a proven-clear path, times it, checks it in time
  against the arms that were moving, and returns a :class:`Plan`.

:meth:`MotionPlanner.plan` does both at once. Nothing moves until
:meth:`MotionPlanner.execute`, which checks a plan made at an earlier step again against
the world as it is then, and refuses it (:class:`StalePlan`) if it no longer holds.

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

from armfleet.checks.number_ranges import CLEARANCE_M
from armfleet.controllers.gripper_joints import finger_indices
from armfleet.controllers.jerk_limited_trajectory import SampledMotion
from armfleet.errors import (
    ArmFault,
    ArmfleetError,
    ArmInMotion,
    ProtectiveStopError,
    UnknownArm,
)
from armfleet.messages import FloatArray, PlannedMotion
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, PlanningLimit
from armfleet.motion.pose_goal import PoseGoal
from armfleet.planning.failure import FailureReason, PlanningFailed
from armfleet.planning.moving_arms import MovingArm, find_start_delay
from armfleet.planning.object_geometry import object_placement, object_shape
from armfleet.planning.path_search import find_path
from armfleet.planning.plan import Plan
from armfleet.planning.planned_arm import PlannedArm
from armfleet.planning.planning_request import (
    ArmRequest,
    PlanningRequest,
    arm_limits,
    goal_state,
)
from armfleet.planning.problem import PlanningProblem
from armfleet.planning.scene import ArmGeometry, SceneObject, arm_geometry
from armfleet.planning.scene_pool import SceneParts, ScenePool, SceneSnapshot
from armfleet.planning.smooth_timing import SmoothPath

if TYPE_CHECKING:
    from armfleet.objects import WorldObject

#: Tool path points drawn per second of motion.
TOOL_PATH_RATE_HZ = 50.0


Goal = Any  # joint positions, or a PoseGoal


class StalePlan(ArmfleetError):
    """A plan made at an earlier step no longer holds: its arms are elsewhere now, or the
    world changed so that it is not clear any more. Nothing moved; plan again."""


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
        self._parts: SceneParts | None = None
        self._scenes = ScenePool()

    # -- planning ------------------------------------------------------------------------
    def plan(
        self,
        goals: Mapping[str, Goal],
        *,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> Plan:
        """Plan ``goals`` (per arm name: joint positions or a :class:`PoseGoal`) jointly,
        within ``timeout_s`` (1 s by default) or ``budget`` iterations (reproducible).

        Raises:
            PlanningFailed: start or goal in collision, goal unreachable, or no path.
            UnknownArm, ArmInMotion, ArmFault, ProtectiveStopError, and the errors of
                ``arm.move_to`` / ``arm.solve_ik`` for bad goals. Nothing moves.
        """
        return self.solve(
            self.prepare(goals, clearance_m=clearance_m, timeout_s=timeout_s, budget=budget)
        )

    def prepare(
        self,
        goals: Mapping[str, Goal],
        *,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> PlanningRequest:
        """Read from the world what planning ``goals`` needs (on the thread that steps it).

        Cheap: no collision check, no IK. Bad requests are refused here, as :meth:`plan`
        refuses them; :meth:`solve` then plans the request on any thread.

        Raises:
            UnknownArm, ArmInMotion, ArmFault, ProtectiveStopError, and the errors of
                ``arm.move_to`` / ``arm.solve_ik`` for bad goals. Nothing moves.
        """
        began = time.perf_counter()
        clearance_m = CLEARANCE_M.check(clearance_m, "clearance_m")
        limit = PlanningLimit.given(timeout_s, budget)
        if not isinstance(goals, Mapping) or not goals:
            raise ArmfleetError("plan takes a mapping {arm name: goal} with at least one arm")
        world_arms = self._arms()
        arms = [self._ready_arm(world_arms, name) for name in goals]
        requests = tuple(self._arm_request(arm, goals[arm.name]) for arm in arms)
        mark = time.perf_counter()
        snapshot = self._snapshot(clearance_m)
        movers = self._moving_arms(world_arms, tuple(arm.name for arm in arms))
        scene_s = time.perf_counter() - mark
        return PlanningRequest(
            arms=requests,
            scene=snapshot,
            movers=tuple(movers),
            clearance_m=clearance_m,
            limit=limit,
            stamp=self._now(),
            read_s=time.perf_counter() - began,
            seconds={"scene": scene_s},
        )

    def solve(self, request: PlanningRequest, *, sampled: bool = False) -> Plan:
        """Plan ``request``; reads nothing of the world, so any thread may run it while
        the world steps (each call takes a scene of its own from the pool).

        Its time budget counts from when it started here, plus the time it took to read.
        With ``sampled``, the motion is also sampled at each arm's controller period
        (:attr:`Plan.sampled`), so that starting it later costs the stepping thread little.

        Raises:
            PlanningFailed: start or goal in collision, goal unreachable, or no path.
        """
        began = time.perf_counter()
        limit = request.limit
        names = request.names
        seconds = dict(request.seconds)
        with self._scenes.scene(request.scene) as scene:
            mark = time.perf_counter()
            for mover in request.movers:
                scene.set_arm_controlled(mover.name, mover.final)
            checker = scene.checker(names)
            seconds["scene"] += time.perf_counter() - mark
            start = request.start
            mark = time.perf_counter()
            goal = goal_state(request, checker)
            seconds["ik"] = time.perf_counter() - mark
            lower, upper = request.bounds(goal)
            problem = PlanningProblem(
                names, start, goal, lower, upper, checker, limit.timeout_s, limit.budget
            )
            path = find_path(problem, deadline=began - request.read_s + limit.timeout_s)
            seconds.update(path.seconds)
            mark = time.perf_counter()
            timed = SmoothPath(path.waypoints, request.limits(), checker)
            seconds["timing"] = time.perf_counter() - mark
            mark = time.perf_counter()
            delay, conflict = find_start_delay(scene, names, timed, request.movers)
            seconds["in_time"] = time.perf_counter() - mark
            checks = checker.checks
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
            joint_names={arm.name: arm.joint_names for arm in request.arms},
            waypoints=path.waypoints,
            duration_s=delay + timed.duration,
            start_delay_s=delay,
            planning_time_s=request.read_s + time.perf_counter() - began,
            collision_checks=checks,
            samples=path.samples,
            clearance_m=request.clearance_m,
            stamp=request.stamp,
            timing=timed,
            seconds=seconds,
            scene=request.scene,
            sampled={arm.period: timed.sample(arm.period) for arm in request.arms}
            if sampled
            else {},
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

    @classmethod
    def _arm_request(cls, arm: PlannedArm, goal: Goal) -> ArmRequest:
        """``arm`` and its goal as they are now: a joint goal checked against its limits, a
        pose goal's frame looked up (its IK runs later, on its own data)."""
        controller = arm.position_controller
        posed = isinstance(goal, PoseGoal)
        return ArmRequest(
            name=arm.name,
            joint_names=arm.joint_names,
            start=cls._start(arm),
            goal=None if posed else controller.validate(goal),
            solve_pose=arm.pose_solver(goal.pose, goal.frame, link=goal.link) if posed else None,
            lower=controller.lower.copy(),
            upper=controller.upper.copy(),
            continuous=_continuous(arm),
            period=controller.period,
            limits=arm_limits(
                controller.max_velocity,
                float(controller.parameters["max_acceleration_rad_s2"]),
                float(controller.parameters["max_jerk_rad_s3"]),
            ),
        )

    # -- the scene -----------------------------------------------------------------------------
    def _snapshot(self, clearance_m: float) -> SceneSnapshot:
        """The world now, as the planner sees it (its parts made again only when they
        changed; otherwise only where everything is)."""
        arms = self._arms()
        objects = self._objects()
        held = self._held_objects(arms, objects)
        key = (
            clearance_m,
            tuple((name, id(arm)) for name, arm in arms.items()),
            tuple((name, id(obj)) for name, obj in objects.items()),
            tuple(sorted(held.items())),
        )
        if self._parts is None or self._parts.key != key:
            geometries = [self._geometry(arm) for arm in arms.values()]
            parts = [
                SceneObject(name, object_shape(obj), pin.SE3.Identity(), held.get(name))
                for name, obj in objects.items()
            ]
            self._parts = SceneParts(key, geometries, parts, clearance_m)
        placements = {}
        for name, obj in objects.items():
            holder = held.get(name)
            if holder is None:
                placements[name] = object_placement(obj)
            else:
                hand = self._geometry(arms[holder]).hand_joint
                assert hand is not None  # only arms with a gripper hold things
                placements[name] = _in_hand(arms[holder], obj, hand)
        positions = {name: arm.body.position.copy() for name, arm in arms.items()}
        return SceneSnapshot(self._parts, positions, placements)

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
            raise StalePlan(
                f"the plan of {' + '.join(plan.arms)} starts elsewhere than the arms are now: "
                "plan again from here"
            )
        delay = plan.start_delay_s
        if self._now() != plan.stamp:
            delay = self._recheck(plan)
        motions = {}
        for arm in arms:
            controller = arm.position_controller
            motion = plan.motion(controller.period)
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
        movers = self._moving_arms(self._arms(), plan.arms)
        snapshot = self._snapshot(plan.clearance_m)
        unchanged = plan.scene is not None and plan.scene.same_as(snapshot)
        if unchanged and not movers and plan.start_delay_s == 0.0:
            return 0.0  # nothing moved since it was proven: the proof holds as it is
        with self._scenes.scene(snapshot) as scene:
            for mover in movers:
                scene.set_arm_controlled(mover.name, mover.final)
            checker = scene.checker(plan.arms)
            failure = plan.timing.first_unclear(checker)
            found = None if failure is None else checker.collision(failure)
            if failure is None:
                delay, conflict = find_start_delay(scene, plan.arms, plan.timing, movers)
        if failure is not None:
            what = f" ({found[0]} / {found[1]})" if found else ""
            raise StalePlan(
                f"the plan of {' + '.join(plan.arms)} is no longer clear: the world changed "
                f"since it was planned{what}; plan again"
            )
        if conflict is not None:
            raise StalePlan(
                f"the plan of {' + '.join(plan.arms)} is no longer clear: {conflict.arm} is "
                "moving through it; plan again"
            )
        return delay


def _continuous(arm: PlannedArm) -> npt.NDArray[np.bool_]:
    """Per joint of ``arm.joint_names``: whether it is continuous (no position limit)."""
    kinematics = arm.kinematics
    mask: npt.NDArray[np.bool_] = kinematics.continuous[kinematics.arm_indices]
    return mask


def _in_hand(arm: PlannedArm, obj: WorldObject, hand: str) -> pin.SE3:
    """Where a held object is in the frame of ``arm``'s joint ``hand``, which holds it."""
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
