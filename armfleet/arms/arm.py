"""The handle users hold for one arm of a world."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import pinocchio as pin

from armfleet import topics
from armfleet.arms.gripper import Gripper
from armfleet.arms.self_contact import SelfContactCheck
from armfleet.checks.flags import flag
from armfleet.checks.real_numbers import STAMP_VALID, real_number
from armfleet.controllers import ControllerManager, JointStateBroadcaster, PositionController
from armfleet.controllers.gripper_controller import GripperController
from armfleet.controllers.jerk_limited_trajectory import MotionPlan
from armfleet.description import ArmDescription
from armfleet.errors import (
    ArmFault,
    ArmfleetError,
    ArmInMotion,
    NoGripper,
    ProtectiveStopError,
    UnknownArm,
    UnreachablePose,
)
from armfleet.frames.robot_state_publisher import RobotStatePublisher
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.kinematics import ArmKinematics
from armfleet.kinematics.inverse_kinematics import (
    InverseKinematics,
    is_pose,
    link_frame,
    world_goal,
)
from armfleet.messages import (
    ArmMode,
    ArmStatus,
    FloatArray,
    JointCommand,
    JointState,
    Positions,
)
from armfleet.motion.cartesian_path import LinearPathPlanner
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, MoveOptions
from armfleet.motion.pose_goal import PoseGoal
from armfleet.motion.timed_trajectory import Rows, Times, check_waypoints, sample_waypoints
from armfleet.physics.arm_body import ArmBody
from armfleet.runtime.bus import Bus
from armfleet.runtime.lifetime import Lifetime, while_alive
from armfleet.safety.safety_supervisor import SafetySupervisor

if TYPE_CHECKING:
    from armfleet.planning import MotionPlanner, Plan


class Arm:
    """One arm: its body, model, controllers and namespace ``/<name>``.

    Created by :meth:`armfleet.World.spawn`; not meant to be built by hand.
    After ``world.remove(name)`` its methods raise :class:`~armfleet.errors.UnknownArm`,
    after ``world.close()`` :class:`~armfleet.errors.WorldClosed` (see
    :mod:`armfleet.runtime.lifetime`), and so do its parts that live in the world (``body``,
    ``kinematics``, the controllers, ``state_publisher``, ``ik``). What it *is* stays
    readable: ``name``, ``namespace``, ``model``, ``pose``, ``joint_names``,
    ``joint_limits``, ``has_gripper``, ``description``.
    """

    def __init__(
        self,
        name: str,
        pose: SpawnPose,
        description: ArmDescription,
        body: ArmBody,
        kinematics: ArmKinematics,
        bus: Bus,
        controller_manager: ControllerManager,
        broadcaster: JointStateBroadcaster,
        position_controller: PositionController,
        state_publisher: RobotStatePublisher,
        safety: SafetySupervisor,
        gripper_controller: GripperController | None = None,
        frame_pose: Callable[[str], FloatArray] | None = None,
        lifetime: Lifetime | None = None,
        planner: MotionPlanner | None = None,
    ) -> None:
        self._name = name
        #: Ended when the arm leaves its world (or the world closes).
        self._lifetime = lifetime or Lifetime(lambda: UnknownArm(name, []))
        self._pose = pose
        self._description = description
        self._body = body
        self._kinematics = kinematics
        self._bus = bus
        self._controller_manager = controller_manager
        self._broadcaster = broadcaster
        self._position_controller = position_controller
        self._state_publisher = state_publisher
        self._safety = safety
        self._gripper_controller = gripper_controller
        self._gripper = (
            None
            if gripper_controller is None
            else Gripper(name, gripper_controller, bus, self._lifetime)
        )
        #: World pose (4x4) of any frame the world knows, for Cartesian goals.
        self._frame_pose = frame_pose
        self._ik = InverseKinematics(kinematics)
        self._linear = LinearPathPlanner(name, self._ik, position_controller)
        #: Refuses a straight motion that would touch the arm itself (built on first use).
        self._self_contact = SelfContactCheck(name, description, kinematics, position_controller)
        #: The world's collision-free planner (None for an arm outside a world).
        self._planner = planner

    # -- what a handle is: readable after close or remove ------------------------------
    @property
    def description(self) -> ArmDescription:
        """The expanded model (URDF, home, link pairs that never touch): what the arm is."""
        return self._description

    # -- the arm in its world: raise after close or remove --------------------------------
    @property
    @while_alive
    def body(self) -> ArmBody:
        """Its PyBullet body (for inspection; command it through the controllers)."""
        return self._body

    @property
    @while_alive
    def kinematics(self) -> ArmKinematics:
        """Its Pinocchio model and data (the data follows the live arm)."""
        return self._kinematics

    @property
    @while_alive
    def controller_manager(self) -> ControllerManager:
        return self._controller_manager

    @property
    @while_alive
    def broadcaster(self) -> JointStateBroadcaster:
        return self._broadcaster

    @property
    @while_alive
    def position_controller(self) -> PositionController:
        return self._position_controller

    @property
    @while_alive
    def state_publisher(self) -> RobotStatePublisher:
        return self._state_publisher

    @property
    @while_alive
    def gripper_controller(self) -> GripperController | None:
        return self._gripper_controller

    @property
    @while_alive
    def ik(self) -> InverseKinematics:
        """Inverse kinematics of this arm (its own Pinocchio data)."""
        return self._ik

    @property
    def lifetime(self) -> Lifetime:
        """Ended once the arm is removed or its world closed."""
        return self._lifetime

    @property
    def name(self) -> str:
        return self._name

    @property
    def namespace(self) -> str:
        return f"/{self._name}"

    @property
    def model(self) -> str:
        return self._description.model

    @property
    def pose(self) -> SpawnPose:
        """Spawn pose of ``<name>_base_link`` in the world."""
        return self._pose

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Prefixed names of the joints :meth:`move_to` controls, base to tool."""
        return self._position_controller.joint_names

    @property
    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        """(lower, upper) position limits of :attr:`joint_names` [rad or m]."""
        return self._position_controller.lower.copy(), self._position_controller.upper.copy()

    @property
    @while_alive
    def gripper(self) -> Gripper:
        """The fingers: ``open()``, ``close(force)``, ``move_to(width)``, ``width``, ``holding``.

        Raises:
            NoGripper: the model has no fingers.
        """
        if self._gripper is None:
            raise NoGripper(self._name, self.model)
        return self._gripper

    @property
    def has_gripper(self) -> bool:
        return self._gripper is not None

    @property
    @while_alive
    def joint_state(self) -> JointState:
        """The latest message of ``/<name>/joint_states`` (every movable joint)."""
        latest = self._broadcaster.latest
        assert latest is not None  # bring-up waits for the first message
        return latest

    @property
    @while_alive
    def positions(self) -> FloatArray:
        """Current positions of :attr:`joint_names`, read at the last step."""
        positions: FloatArray = self._body.position[self._kinematics.arm_indices].copy()
        return positions

    @property
    @while_alive
    def is_moving(self) -> bool:
        """Whether the position controller's reference is still in motion."""
        return self._position_controller.is_moving

    @while_alive
    def status(self, stamp: float) -> ArmStatus:
        """What the arm is doing now (also published on ``/<name>/status``), stamped
        ``stamp`` [s of simulated time].

        Raises:
            InvalidNumber: ``stamp`` is not a finite number >= 0 (text, bool, None).
        """
        stamp = real_number(stamp, f"{self._name}: stamp", STAMP_VALID, low=0.0)
        controller = self._position_controller
        fault = self._controller_manager.fault
        if fault is not None:
            mode, reason = ArmMode.ERROR, fault
        elif controller.stop_reason is not None:
            mode, reason = ArmMode.PROTECTIVE_STOP, controller.stop_reason
        else:
            mode, reason = (ArmMode.MOVING if controller.is_moving else ArmMode.HOLDING), ""
        return ArmStatus(
            stamp, self._name, mode, reason, tuple(controller.saturation_steps.tolist())
        )

    @property
    def mode(self) -> ArmMode:
        return self.status(0.0).mode

    @while_alive
    def reset_stop(self) -> None:
        """Accept commands again after a protective stop (the arm holds where it stopped).

        The arm may then move away from what it touches without stopping again.
        """
        self._safety.reset_stop(self)

    @while_alive
    def reset(self) -> None:
        """Leave ``error`` (restarting the controllers at the current pose) and any stop."""
        self._controller_manager.reset()
        self._safety.reset_stop(self)

    @while_alive
    def move_to(
        self,
        positions: Positions,
        *,
        avoid_collisions: bool = False,
        clearance_m: float | None = None,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> float:
        """Send target ``positions`` (one per :attr:`joint_names`); returns at once.

        Returns the planned duration of the motion [s].

        The command goes out on ``/<name>/position_controller/commands``. With
        ``avoid_collisions=True`` the arm goes around everything in the world instead
        of in a straight line, keeping ``clearance_m`` from other bodies (see
        :meth:`plan`); it must be at rest.

        A straight motion that would bring the arm within 1 mm of itself, at the target
        or on the way (the jerk-limited path it follows), is refused, as spawn refuses
        such a start (see :mod:`armfleet.arms.self_contact`).

        Raises:
            TargetLengthError, NonFiniteTarget, JointLimitError, MotionLimitError,
            SelfContactError (naming the two links), ProtectiveStopError, ArmFault:
            nothing is sent and the current motion goes on.
            PlanningFailed, ArmInMotion: with ``avoid_collisions``; nothing moves.
        """
        options = MoveOptions.given(avoid_collisions, clearance_m, timeout_s, budget)
        if options.avoid_collisions:
            planned = self.plan(positions, **options.plan_keywords())
            return self._world_planner().execute(planned)
        values = self._position_controller.validate(positions)
        if self._controller_manager.fault is not None:
            raise ArmFault(self._name, self._controller_manager.fault)
        motion = self._position_controller.plan(values)
        self.check_self_contact(motion)
        self._publish_command(values)
        return motion.duration

    @while_alive
    def plan(
        self,
        target: Any,
        frame: str = "world",
        *,
        link: str = "tool0",
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> Plan:
        """A collision-free motion to ``target``, without moving (``world.execute(plan)``).

        Args:
            target: joint positions (one per :attr:`joint_names`), or a pose (4x4 or
                ``pinocchio.SE3``) of ``link`` in ``frame``, as :meth:`move_to_pose`.
            frame, link: for a pose target.
            clearance_m: margin kept from other bodies [m], in [0.001, 0.5].
            timeout_s: time budget [s], in [0.001, 60]; 1 s when neither it nor
                ``budget`` is given.
            budget: work budget instead: RRT-Connect iterations, an integer in
                1..1000000. The same request gives the same path in any process,
                under any load (see :mod:`armfleet.planning.ompl_search`).

        Every other arm is an obstacle where it is; one that is moving is checked in
        time, along its remaining motion. See :mod:`armfleet.planning`.

        Raises:
            PlanningFailed: the start or goal is in collision (the links named), the
                pose is unreachable, or no path was found in ``timeout_s`` (or
                ``budget``).
            ArmInMotion, ArmFault, ProtectiveStopError, and the target errors of
            :meth:`move_to` and :meth:`solve_ik`.
        """
        goal = PoseGoal(target, frame, link) if is_pose(target) else target
        return self._world_planner().plan(
            {self._name: goal}, clearance_m=clearance_m, timeout_s=timeout_s, budget=budget
        )

    @while_alive
    def check_self_contact(self, motion: MotionPlan) -> None:
        """Raise :class:`~armfleet.errors.SelfContactError` if ``motion`` (made by the
        position controller from its reference, not yet followed) would bring the arm
        within 1 mm of itself, at its target or on the way."""
        self._self_contact.check_plan(motion, self._body.position)

    def _world_planner(self) -> MotionPlanner:
        if self._planner is None:
            raise ArmfleetError(f"{self._name} is not in a world that plans")
        return self._planner

    def _publish_command(self, values: FloatArray) -> None:
        self._bus.publish(
            topics.position_commands(self.name),
            JointCommand(tuple(float(v) for v in values)),
        )

    @while_alive
    def solve_ik(
        self,
        pose: Any,
        frame: str = "world",
        *,
        link: str = "tool0",
        seed: Positions | None = None,
    ) -> FloatArray:
        """Arm joint positions (one per :attr:`joint_names`) that put ``link`` at ``pose``.

        Args:
            pose: 4x4 homogeneous matrix (or ``pinocchio.SE3``) of ``link`` in ``frame``.
            frame: any frame of the world's TF tree (``world``, links, objects).
            link: a frame of this arm, unprefixed (``tool0``) or prefixed (``bob_tool0``).
            seed: first guess; the measured positions by default. The solution
                nearest the seed is preferred (see :mod:`armfleet.kinematics.inverse_kinematics`).

        Raises:
            UnreachablePose: with the residual; TargetPoseError, UnknownFrame,
                TargetLengthError, JointLimitError (seed).
        """
        goal, link_frame = self._resolve(pose, frame, link)
        start = self._body.position.copy()
        if seed is not None:
            start[self._kinematics.arm_indices] = self._position_controller.validate(seed)
        solution = self._ik.solve(link_frame, goal, start)
        if not solution.converged:
            raise UnreachablePose(
                self._name, link, solution.position_error_m, solution.rotation_error_rad
            )
        positions: FloatArray = solution.positions[self._kinematics.arm_indices].copy()
        return positions

    @while_alive
    def move_to_pose(
        self,
        pose: Any,
        frame: str = "world",
        *,
        link: str = "tool0",
        linear: bool = False,
        avoid_collisions: bool = False,
        clearance_m: float | None = None,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> float:
        """Move ``link`` to ``pose`` (in ``frame``); returns at once the planned duration [s].

        With ``linear=True`` the link goes in a straight line from where it is
        (its orientation turning about one axis), jerk-limited and within the
        joint limits; the arm must be at rest. With ``avoid_collisions=True`` the
        arm goes around everything in the world (see :meth:`plan`). On any error
        nothing moves and the current motion goes on.

        Raises:
            UnreachablePose, ArmInMotion, and the errors of :meth:`solve_ik` and
            :meth:`move_to`; PlanningFailed with ``avoid_collisions``.
        """
        linear = flag(linear, "linear")
        options = MoveOptions.given(avoid_collisions, clearance_m, timeout_s, budget)
        if options.avoid_collisions:
            if linear:
                raise ArmfleetError(
                    f"{self._name}: choose linear=True (a straight tool line) or "
                    "avoid_collisions=True (a planned path around obstacles), not both"
                )
            plan = self.plan(pose, frame, link=link, **options.plan_keywords())
            return self._world_planner().execute(plan)
        if self._controller_manager.fault is not None:
            raise ArmFault(self._name, self._controller_manager.fault)
        controller = self._position_controller
        if controller.stop_reason is not None:
            raise ProtectiveStopError(self._name, controller.stop_reason)
        if not linear:
            return self.move_to(self.solve_ik(pose, frame, link=link))
        if controller.is_moving or controller.trajectory is None:
            raise ArmInMotion(self._name, "a linear move")
        goal, link_frame = self._resolve(pose, frame, link)
        start = self._body.position.copy()
        start[self._kinematics.arm_indices] = controller.trajectory.position
        motion = self._linear.plan(link_frame, link, start, goal)
        controller.check_samples(motion)
        self._self_contact.check_samples(
            controller.trajectory.position, motion, controller.period, self._body.position
        )
        self._publish_command(motion.position[-1])  # for the record; the samples replace it
        controller.follow_samples(motion)
        return motion.steps * controller.period

    @while_alive
    def follow_trajectory(
        self,
        times: Times,
        positions: Rows,
        velocities: Rows | None = None,
        accelerations: Rows | None = None,
    ) -> float:
        """Follow timed waypoints from the present reference (replacing any motion), as
        joint_trajectory_controller does with a ``JointTrajectory``; returns at once.

        Args:
            times: each waypoint's time after now [s], increasing, the first > 0.
            positions: per waypoint, one position per joint (:attr:`joint_names`).
            velocities, accelerations: per waypoint, or None: with all three, a quintic
                per segment; with velocities, a cubic; with positions only, a smooth
                cubic through them (:mod:`armfleet.motion.timed_trajectory`). The last
                point is at rest.

        Returns:
            The trajectory's duration [s].

        Raises:
            TrajectoryRefused (empty, lengths, not finite, times not increasing, not at
            rest at the end), ArmfleetError (the samples leave the joint position,
            velocity or acceleration limits), SelfContactError, ProtectiveStopError,
            ArmFault: nothing is sent and the current motion goes on.
        """
        controller = self._position_controller
        waypoints = check_waypoints(
            self._name, len(self.joint_names), times, positions, velocities, accelerations
        )
        if self._controller_manager.fault is not None:
            raise ArmFault(self._name, self._controller_manager.fault)
        if controller.stop_reason is not None:
            raise ProtectiveStopError(self._name, controller.stop_reason)
        reference = controller.trajectory
        if reference is None:
            raise ArmfleetError(f"{self._name}: position_controller is not active")
        start = (
            reference.position.copy(),
            reference.velocity.copy(),
            reference.acceleration.copy(),
        )
        motion = sample_waypoints(waypoints, start, controller.period)
        controller.check_samples(motion)
        self._self_contact.check_samples(start[0], motion, controller.period, self._body.position)
        self._publish_command(motion.position[-1])  # for the record; the samples replace it
        controller.follow_samples(motion)
        return motion.steps * controller.period

    @while_alive
    def halt(self) -> float:
        """Bring the motion to rest within the controller's limits and hold there (what
        a cancelled trajectory does). Returns the stopping time [s]."""
        return self._position_controller.halt()

    def _resolve(self, pose: Any, frame: str, link: str) -> tuple[pin.SE3, str]:
        """The world pose wanted for ``link`` and the link's prefixed frame name."""
        name = link_frame(self._name, self._kinematics, self._description.prefix, link)
        return world_goal(pose, frame, self._frame_pose), name

    def __repr__(self) -> str:
        return f"Arm({self._name!r}, model={self.model!r}, pose={self._pose})"
