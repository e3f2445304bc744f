"""One PyBullet world holding several arms, stepped by one thread at a fixed dt."""

from __future__ import annotations

import builtins
import logging
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Future
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import pybullet as p

from armfleet import topics
from armfleet.arms.arm import Arm
from armfleet.arms.arm_assembly import (
    ControllerOverrides,
    assemble_arm,
    check_controller_parameters,
    start_positions,
)
from armfleet.arms.arm_driver import ArmDriver
from armfleet.checks.flags import flag
from armfleet.checks.names import check_arm_name
from armfleet.checks.number_ranges import (
    DEFAULT_FOXGLOVE_RATE_HZ,
    DEFAULT_ROS_RATE_HZ,
    PORT,
    RUN_DURATION_S,
)
from armfleet.checks.real_numbers import real_number
from armfleet.checks.time_step import check_dt
from armfleet.controllers.fleet_update import FleetUpdate
from armfleet.description import ModelLibrary
from armfleet.description.model_options import options_from_keywords
from armfleet.errors import ArmfleetError, NameInUse, UnknownArm, WorldClosed
from armfleet.frames.frame_registry import FrameOwner, FrameRegistry, arm_frames
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.frames.tf_tree import TfTree
from armfleet.kinematics import ArmKinematics
from armfleet.kinematics.inverse_kinematics import is_pose
from armfleet.messages import (
    BringupEvent,
    Contact,
    FloatArray,
    Positions,
)
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, MoveOptions
from armfleet.motion.synchronised_motion import move_together
from armfleet.objects import ObjectSet, WorldObject, object_spec
from armfleet.objects.arm_path_clearance import ArmMotion
from armfleet.objects.object_spec import (
    DEFAULT_COLOR,
    DEFAULT_FRICTION,
    DEFAULT_MASS_KG,
    DEFAULT_ROLLING_FRICTION_M,
    DEFAULT_SPINNING_FRICTION_M,
)
from armfleet.physics.collision_filter import fixed_links
from armfleet.physics.contact_monitor import ContactMonitor
from armfleet.physics.ground import create_ground
from armfleet.physics.joint_memory import JointMemory
from armfleet.planning import MotionPlanner, Plan, PoseGoal
from armfleet.runtime.bus import Bus
from armfleet.runtime.lifetime import Lifetime
from armfleet.runtime.request_queue import Deferred, RequestQueue
from armfleet.runtime.step_guard import StepGuard, owning
from armfleet.safety.safety_supervisor import SafetySupervisor
from armfleet.world.bringup import bring_up
from armfleet.world.front_ends import ViewerHandle, front_end
from armfleet.world.planned_moves import PlannedMoves
from armfleet.world.world_listener import WorldListener
from armfleet.world.world_snapshot import WorldSnapshot

if TYPE_CHECKING:
    from armfleet.spec import FleetSpec

logger = logging.getLogger("armfleet")

#: Period of the ``/<arm>/status`` reports [s].
STATUS_PERIOD_S = 0.1

T = TypeVar("T")


class World:
    """A PyBullet world (DIRECT mode) with gravity, a floor at z = 0 and arms.

    Args:
        dt: physics step [s], in [``MIN_DT_S``, ``MAX_DT_S``] of :mod:`armfleet.checks.time_step`.
        gravity: gravitational acceleration along -z [m/s^2], in [-100, 100].
        models: library of arm models; armfleet's ``description/`` by default.
        viewer: start a MeshCat viewer (``world.viewer.url``); if it cannot
            start, the world runs without it and the reason is logged.
        viewer_port: web port of the viewer (1..65535); a free one by default.
        compiled_control: update the position controllers of arms on the fleet path in
            compiled code (``cpp/``); False: in numpy, the reference it is
            tested against. Results agree to 1e-12 (docs/performance.md).
    """

    def __init__(
        self,
        dt: float = 0.001,
        gravity: float = 9.81,
        models: ModelLibrary | None = None,
        *,
        viewer: bool = False,
        viewer_port: int | None = None,
        compiled_control: bool = True,
    ) -> None:
        dt = check_dt(dt)
        viewer = flag(viewer, "viewer")
        compiled_control = flag(compiled_control, "compiled_control")
        if viewer_port is not None:
            PORT.check(viewer_port, "viewer_port")  # as the CLI's --viewer-port
        gravity = real_number(gravity, "gravity", "[-100, 100] m/s^2", low=-100.0, high=100.0)
        self._dt = dt
        self._client: int = p.connect(p.DIRECT)
        p.setTimeStep(dt, physicsClientId=self._client)
        p.setGravity(0.0, 0.0, -gravity, physicsClientId=self._client)
        self._ground = create_ground(self._client)
        if models is not None and not isinstance(models, ModelLibrary):
            raise ArmfleetError(
                f"models must be an armfleet.description.ModelLibrary (or None for the "
                f"shipped models), got {type(models).__name__}"
            )
        self._models = models or ModelLibrary()
        self._bus = Bus(clock=lambda: self.time)
        self._bus.advertise(topics.BRINGUP, BringupEvent)
        self._arms: dict[str, Arm] = {}
        self._memory = JointMemory(self._client)
        self._compiled_control = compiled_control
        self._controllers = FleetUpdate(self._memory, compiled=compiled_control)
        self._step_index = 0
        self._stepping_s = 0.0
        #: Ended by close(); every arm's lifetime is a child of it.
        self._lifetime = Lifetime(WorldClosed)
        self._contacts = ContactMonitor(self._client, self._ground, self._bus, self._on_contact)
        self._objects = ObjectSet(
            self._client, self._bus, self._contacts, self._lifetime, self.remove_object
        )
        self._tf = TfTree(self._arm_states, lambda: self._objects.objects, self._lifetime)
        self._frames = FrameRegistry()  # every frame has one owner: arm or object
        self._safety = SafetySupervisor(
            self._contacts, lambda: self._arms, lambda arm: self._publish_status(self.arm(arm.name))
        )
        self._status_period_steps = max(1, round(STATUS_PERIOD_S / dt))
        self._requests = RequestQueue()
        self._guard = StepGuard(self.close)  # one thread at a time, never inside a step
        #: What the planner and synchronised motions drive, per arm (not the user's handle).
        self._drivers: dict[str, ArmDriver] = {}
        self._planner = MotionPlanner(
            lambda: self._drivers,
            lambda: self._objects.objects,
            self._contacts.touching_bodies,
            lambda: self.time,
        )
        #: Planned moves asked by other threads, planned off the stepping thread.
        self._planned_moves = PlannedMoves(self._planner, self.submit)
        #: Front ends attached to the world (viewer, Foxglove, ...), in attach order.
        self._listeners: list[WorldListener] = []
        self._viewer: ViewerHandle | None = None
        self.viewer_error: str | None = None
        if viewer:  # MeshCat is only loaded when asked for
            self._viewer, self.viewer_error = front_end("viewer")(self, viewer_port)

    # -- properties -------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """Physics step [s]."""
        return self._dt

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return self._step_index * self._dt

    @property
    def bus(self) -> Bus:
        return self._bus

    @property
    def tf(self) -> TfTree:
        return self._tf

    @property
    def models(self) -> ModelLibrary:
        return self._models

    @property
    def arms(self) -> dict[str, Arm]:
        """Arms by name, in bring-up order."""
        return dict(self._arms)

    @property
    def viewer(self) -> ViewerHandle | None:
        """The MeshCat viewer (an :class:`armfleet.viewer.Viewer`), or None (not asked
        for, or it could not start: :attr:`viewer_error` says why)."""
        return self._viewer

    def attach(self, listener: WorldListener) -> None:
        """Let ``listener`` hear of arms, objects, steps and the close (front ends do).

        Call it from the thread that steps the world, or hand it over with :meth:`submit`.
        """
        self._check_open()
        if not isinstance(listener, WorldListener):
            raise ArmfleetError(
                f"attach takes an armfleet.world.WorldListener, got {type(listener).__name__}"
            )
        if listener not in self._listeners:
            self._listeners.append(listener)

    @property
    def listener_count(self) -> int:
        """Front ends attached (:meth:`attach`)."""
        return len(self._listeners)

    def detach(self, listener: WorldListener) -> None:
        """Stop calling ``listener`` (nothing happens if it is not attached)."""
        if listener in self._listeners:
            self._listeners.remove(listener)

    def _tell(self, hook: Callable[[WorldListener], None]) -> None:
        for listener in tuple(self._listeners):
            try:
                hook(listener)
            except Exception:  # a front end never stops the world
                logger.exception("front end %s failed; detached", type(listener).__name__)
                self.detach(listener)

    @property
    def step_guard(self) -> StepGuard:
        """Which thread may step or change the world now (:mod:`armfleet.runtime.step_guard`)."""
        return self._guard

    @property
    def physics_client(self) -> int:
        """PyBullet client id of this world (for inspection; don't step it yourself)."""
        return self._client

    def submit(self, function: Callable[[], T]) -> Future[T]:
        """Run ``function`` in the stepping thread at the next step boundary (thread-safe).

        This is how other threads (a server, a client) act on the world: spawning,
        moving, removing, reading, all happen between two steps, in order.
        """
        self._check_open()
        if not callable(function):
            raise ArmfleetError(
                f"submit takes a function of no arguments, got {type(function).__name__}"
            )
        return self._requests.submit(function)

    def record(
        self,
        path: str | Path,
        *,
        spec: FleetSpec | None = None,
        topics: Iterable[str] | None = None,
    ) -> Any:
        """Record every topic (or only ``topics``) to the MCAP file ``path``.

        Returns the running :class:`armfleet.Recorder`: stop it, or use it in a
        ``with`` block. ``spec`` is attached to the file when given. Same as
        :func:`armfleet.record`.
        """
        return front_end("recorder")(self, path, spec=spec, topics=topics)

    @owning  # it subscribes to the bus: never from another thread during a step
    def serve_foxglove(
        self,
        port: int = 0,
        *,
        host: str = "127.0.0.1",
        rate_hz: float | None = DEFAULT_FOXGLOVE_RATE_HZ,
    ) -> Any:
        """Serve this world to Foxglove on ``ws://HOST:PORT`` (docs/foxglove.md).

        Every topic (the recording's schemas, JSON), the arms' URDFs and meshes, and the
        services ``/move``, ``/move_together``, ``/grip``, ``/reset``. Call it from the
        thread that steps the world; keep stepping for clients to be served.

        Args:
            port: TCP port, 0 for a free one (``server.port``); Foxglove proposes 8765.
            host: address to listen on; anything but loopback lets other machines
                command the arms.
            rate_hz: instants of the streamed topics (``/tf``, joint, controller and
                gripper states) sent per simulated second; None: every step.

        Returns:
            The running :class:`armfleet.foxglove.FoxgloveServer`; close it, or it
            closes with the world.

        Raises:
            FoxgloveError: bad host, port or rate, the port is taken, or the world is closed.
            WorldBusy: called from inside a step (a bus subscriber), or from another
                thread while one steps the world (hand it over with :meth:`submit`).
        """
        # foxglove-sdk is loaded only now; without the extra, one line says how to add it.
        return front_end("foxglove")(self, port, host=host, rate_hz=rate_hz)

    @owning  # it subscribes to the bus: never from another thread during a step
    def serve_ros(
        self,
        domain_id: int | None = None,
        *,
        localhost_only: bool = True,
        rate_hz: float = DEFAULT_ROS_RATE_HZ,
    ) -> Any:
        """Serve this world to ROS 2 nodes (docs/ros2.md): ``/clock``, ``/tf``,
        ``/tf_static`` and each arm's ros2_control interfaces (joint states, robot
        description, joint_trajectory_controller's action and topic, the forward position
        controller's commands, the gripper's action). Call it from the thread that steps
        the world; keep stepping for nodes to be served.

        Args:
            domain_id: the ROS domain (0..232); None: ``ROS_DOMAIN_ID``, or 0.
            localhost_only: keep discovery and traffic on this machine (the default).
            rate_hz: instants of the streamed topics per simulated second.

        Returns:
            The running :class:`armfleet.ros.RosServer`; close it, or it closes with
            the world.

        Raises:
            RosError: bad domain or rate, or the world is closed.
            MissingExtra: ROS 2 is not installed (the one-line install command).
        """
        # rclpy is loaded only now; without it, one line says how to install it.
        return front_end("ros")(self, domain_id, localhost_only=localhost_only, rate_hz=rate_hz)

    def process_requests(self) -> int:
        """Run the submitted requests now (the stepping thread calls this; also when paused)."""
        return self._requests.drain()

    def arm(self, name: str) -> Arm:
        if not isinstance(name, str) or name not in self._arms:  # a list is no name either
            raise UnknownArm(name, list(self._arms))
        return self._arms[name]

    def move_together(
        self,
        targets: Mapping[str, Positions | Any],
        *,
        avoid_collisions: bool = False,
        clearance_m: float | None = None,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> float:
        """Move several arms so they start on the same step and finish at the same instant.

        Args:
            targets: per arm name, joint positions (one per ``arm.joint_names``),
                a 4x4 world pose of its tool0 (solved by IK), or a
                :class:`~armfleet.planning.PoseGoal` (any link, any frame).
            avoid_collisions: plan the arms jointly, in their combined joint space,
                around each other and everything else (see :meth:`plan`), instead of
                each in a straight line.
            clearance_m, timeout_s, budget: of the plan, with ``avoid_collisions``
                (see :meth:`plan`).

        Returns:
            The common duration [s]: the longest of the arms' own fastest motions.

        Raises:
            ArmfleetError: an unknown arm or any bad target; then no arm moves.
            PlanningFailed: with ``avoid_collisions``, no plan; then no arm moves.
        """
        self._check_open()
        if not isinstance(targets, Mapping):
            raise ArmfleetError(
                f"move_together takes a mapping {{arm name: target}}, got {type(targets).__name__}"
            )
        options = MoveOptions.given(avoid_collisions, clearance_m, timeout_s, budget)
        if options.avoid_collisions:
            plan = self.plan(targets, **options.plan_keywords())
            return self._planner.execute(plan)
        for name in targets:
            self.arm(name)  # UnknownArm lists the arms
        return move_together({name: (self._drivers[name], t) for name, t in targets.items()})

    def plan(
        self,
        targets: Mapping[str, Positions | Any],
        *,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> Plan:
        """A collision-free motion of the named arms, planned jointly, without moving.

        Args:
            targets: per arm name, as :meth:`move_together` takes them.
            clearance_m: margin kept between different bodies [m], in [0.001, 0.5].
            timeout_s: time budget of the request [s], in [0.001, 60]; 1 s when
                neither it nor ``budget`` is given.
            budget: work budget instead: RRT-Connect iterations (an integer in
                1..1000000); the same request then gives the same path in any process,
                under any load.

        Returns:
            The :class:`~armfleet.planning.Plan`: its path, duration, planning time and
            collision checks; run it with :meth:`execute`.

        Raises:
            PlanningFailed: start or goal in collision (the links named), a pose goal
                unreachable, or no path within ``timeout_s`` or ``budget``; ``blocking_arm`` names a
                moving arm that was in the way.
            ArmfleetError: an unknown arm, a moving or stopped arm, a bad target.
        """
        self._check_open()
        if not isinstance(targets, Mapping):
            raise ArmfleetError(
                f"plan takes a mapping {{arm name: target}}, got {type(targets).__name__}"
            )
        # A 4x4 is tool0 in the world, as move_together takes it.
        goals = {name: PoseGoal(t) if is_pose(t) else t for name, t in targets.items()}
        return self._planner.plan(
            goals, clearance_m=clearance_m, timeout_s=timeout_s, budget=budget
        )

    def execute(self, plan: Plan) -> float:
        """Start ``plan`` on its arms, all on the next step; returns its duration [s].

        A plan made at an earlier step is checked again against the world as it is.

        Raises:
            ArmfleetError: the arms are not where the plan starts, or the world changed
                so that the plan is no longer clear; nothing moves.
        """
        self._check_open()
        return self._planner.execute(plan)

    def start_planned_move(
        self, targets: Mapping[str, Positions | Any], reply: Callable[[float], T], **options: Any
    ) -> Deferred[T]:
        """Plan ``targets`` on a worker thread while the world goes on stepping, then start
        the motion at a step boundary: for front ends that serve other threads (the live
        API). Call it on the stepping thread (in a function given to :meth:`submit`, which
        may return the answer: the request then completes with it).

        A plan that no longer holds when it is ready (another command moved its arm
        meanwhile, or the world changed in its way) is planned again once from where the
        arms are then, or refused in one line (:mod:`armfleet.world.planned_moves`).

        Args:
            targets: per arm name, as :meth:`plan` takes them.
            reply: called with the motion's duration [s] on the stepping thread, right
                after the start; its result is the answer.
            options: of the plan, as :meth:`plan` takes them (``clearance_m``, ...).

        Returns:
            The answer: ``reply``'s result, or the error that stopped the move.

        Raises:
            ArmfleetError: as :meth:`plan` raises it for a request it refuses at once
                (unknown arm, an arm moving, a bad target or option); nothing moves.
        """
        self._check_open()
        if not isinstance(targets, Mapping):
            raise ArmfleetError(
                f"plan takes a mapping {{arm name: target}}, got {type(targets).__name__}"
            )
        goals = {name: PoseGoal(t) if is_pose(t) else t for name, t in targets.items()}
        return self._planned_moves.start(goals, options, reply)

    # -- bring-up ---------------------------------------------------------------------
    @owning
    def spawn(
        self,
        name: str,
        model: str = "panda",
        at: Sequence[float] | SpawnPose = (0.0, 0.0),
        *,
        initial_positions: Positions | None = None,
        parameters: ControllerOverrides | None = None,
        parameter_files: Mapping[str, str | Path] | None = None,
        xacro_args: Mapping[str, str] | None = None,
        tool_link: str | None = None,
        gripper_joints: Sequence[str] | None = None,
        home: Positions | None = None,
        end_effector: Mapping[str, Any] | str | None = None,
    ) -> Arm:
        """Bring an arm up, stage by stage, and return it once ready.

        Stages (each published on ``/bringup``): spawned -> joint_state_broadcaster
        active (first joint state seen) -> position_controller active -> ready
        (holding its pose). Nothing else is brought up meanwhile.

        Args:
            name: arm name (``^[a-z][a-z0-9_]*$``), its namespace and prefix.
            model: one of :attr:`models` ``.names``, a named model of your own
                (``.available``; :mod:`armfleet.description.own_models`), or a robot
                description of your own: a ``.urdf`` or ``.urdf.xacro`` file (relative to
                the working folder) or a ``package://pkg/path`` URI, prefixed and placed
                for you (:mod:`armfleet.description.file_model`; docs/own-robot.md).
            at: ``(x, y[, z[, yaw_deg]])`` of ``<name>_base_link`` [m, deg].
            initial_positions: arm joint positions at spawn; the model's home by default.
            parameters: per-controller parameter overrides for this arm only,
                e.g. ``{"position_controller": {"kp_s2": 900.0}}``.
            parameter_files: per-controller parameter file for this arm; the
                shipped ``controllers/<type>.yaml`` by default.
            xacro_args: arguments of a xacro model file (``{"ur_type": "ur5e"}``).
            tool_link, gripper_joints, home, end_effector: what a model file does not
                say, or says otherwise than you mean (inferred if None): the link
                ``<name>_tool0`` is put on; the gripper's joints; one home value per arm
                joint [rad or m], clear of the arm itself and the floor; a gripper
                description attached at a link (``{"file": ..., "at_link": "tool0",
                "xacro_args": {...}}``). See
                :mod:`armfleet.description.model_options`.

        Raises:
            StartPoseCollision: at its start configuration the arm would touch
                itself, the floor, another arm or an object (nothing is spawned).
            FrameInUse: one of its frames (``<name>_<link>``) is another arm's or an
                object's.
            ArmfleetError: bad name, model, pose or positions; the world is unchanged.
        """
        self._check_open()
        check_arm_name(name, self._arms)
        self._check_name_free(name, "an object" if name in self._objects else "")
        pose = SpawnPose.from_values(at)
        files = check_controller_parameters(parameters or {}, parameter_files or {})
        options = options_from_keywords(
            "spawn",
            xacro_args=xacro_args,
            tool_link=tool_link,
            gripper_joints=gripper_joints,
            home=home,
            end_effector=end_effector,
        )
        description = self._models.expand(model, f"{name}_", pose, options=options)
        kinematics = ArmKinematics(description.urdf, description.tool0)
        start = start_positions(name, kinematics, description.home, initial_positions)
        frames = arm_frames(kinematics)
        self._frames.check(FrameOwner.arm(name), frames)
        started = time.perf_counter()
        arm = assemble_arm(
            name=name,
            pose=pose,
            description=description,
            kinematics=kinematics,
            start=start,
            client=self._client,
            ground=self._ground,
            bus=self._bus,
            dt=self._dt,
            stamp=self.time,
            safety=self._safety,
            on_fault=lambda reason: self._publish_status(self._arms[name]),
            parameters=parameters or {},
            parameter_files=files,
            frame_pose=self._tf.world_pose,
            neighbours=self._contacts.neighbours(),
            lifetime=Lifetime(lambda: UnknownArm(name, list(self._arms)), self._lifetime),
            planner=self._planner,
            compiled=self._compiled_control,
        )
        self._arms[name] = arm
        self._drivers[name] = ArmDriver(arm, self._bus, self._tf.world_pose)
        self._frames.claim(FrameOwner.arm(name), frames)
        self._controllers.lay_out(self._arms.values())
        self._contacts.add_arm(name, arm.body)
        try:
            with self._requests.held():  # nobody else's request inside this bring-up
                bring_up(self, arm, started, on_ready=self._show)
        except BaseException:
            self._remove(arm)
            raise
        return arm

    def _show(self, arm: Arm) -> None:
        self._tell(lambda listener: listener.on_arm_ready(arm))

    @owning
    def remove(self, name: str) -> None:
        """Take the arm ``name`` out of the world: controllers, topics, transforms, body."""
        self._check_open()
        self._remove(self.arm(name))

    def _remove(self, arm: Arm) -> None:
        self._tell(lambda listener: listener.on_arm_removed(arm.name))
        arm.controller_manager.shutdown()
        self._contacts.remove_arm(arm.body)
        arm.state_publisher.close()
        arm.body.remove()
        arm.lifetime.end()  # the handles users hold raise UnknownArm from now on
        del self._arms[arm.name]
        del self._drivers[arm.name]
        self._frames.release(FrameOwner.arm(arm.name))
        self._controllers.lay_out(self._arms.values())
        self._bus.unadvertise(arm.namespace, f"arm {arm.name} was removed")  # subscribers told

    # -- objects ----------------------------------------------------------------------
    @property
    def objects(self) -> dict[str, WorldObject]:
        """Scene objects by name, in the order they were added (a copy)."""
        return self._objects.objects

    def object(self, name: str) -> WorldObject:
        """The scene object ``name``; :class:`armfleet.UnknownObject` lists the others."""
        return self._objects.get(name)

    @owning
    def add_object(
        self,
        name: str,
        shape: str,
        *,
        size: float | Sequence[float] | None = None,
        mass: float = DEFAULT_MASS_KG,
        friction: float = DEFAULT_FRICTION,
        color: Sequence[float] = DEFAULT_COLOR,
        at: Sequence[float] = (0.0, 0.0, 0.0),
        rpy_deg: Sequence[float] = (0.0, 0.0, 0.0),
        mesh: str | Path | None = None,
        scale: float = 1.0,
        spinning_friction: float = DEFAULT_SPINNING_FRICTION_M,
        rolling_friction: float = DEFAULT_ROLLING_FRICTION_M,
    ) -> WorldObject:
        """Add a box, cylinder, sphere or mesh to the world; a table is a static box.

        The object's frame (on ``/tf``, child of ``world``, named ``name``) is
        the centre of a box, cylinder or sphere and the origin of a mesh file.

        Args:
            name: object name (``^[a-z][a-z0-9_]*$``), unique among arms and objects.
            shape: ``"box"``, ``"cylinder"``, ``"sphere"`` or ``"mesh"``.
            size: box (x, y, z) full extents; cylinder (radius, length), axis
                along the object's z; sphere radius (a number or (r,)) [m].
                None for a mesh (its file gives it).
            mass: [kg]; 0 makes the object static, fixed in the world.
            friction: lateral friction coefficient.
            color: RGBA, each in [0, 1].
            at: (x, y, z) of the object's frame [m].
            rpy_deg: roll, pitch, yaw [deg] (R = Rz(yaw) Ry(pitch) Rx(roll)).
            mesh: path of a .obj or .stl file (mesh only); a moving mesh
                collides as its convex hull, a static one as it is.
            scale: scale of the mesh file's coordinates (e.g. 0.001 for mm).
            spinning_friction: torsional friction [m], keeps a held box from turning.
            rolling_friction: rolling resistance [m].

        Raises:
            FrameInUse: an arm owns a frame named ``name`` already.
            ObjectCollision: it would touch an arm, or overlap the floor or an object.
            ObjectInArmPath: it stands in the remaining path of a moving arm (the arm is
                named); checked against the arms' references, as planning checks them.
            ArmfleetError: a bad argument or a name in use; the world is unchanged.
        """
        self._check_open()
        spec = object_spec(
            name,
            shape,
            size=size,
            mass=mass,
            friction=friction,
            spinning_friction=spinning_friction,
            rolling_friction=rolling_friction,
            color=color,
            at=at,
            rpy_deg=rpy_deg,
            mesh=mesh,
            scale=scale,
        )
        kind = "an arm" if name in self._arms else ("an object" if name in self._objects else "")
        self._check_name_free(name, kind)
        owner = FrameOwner.object(name)
        self._frames.claim(owner, (name,))
        try:
            obj = self._objects.add(spec, self.time, self._arm_motions())
        except BaseException:
            self._frames.release(owner)
            raise
        self._tell(lambda listener: listener.on_object_added(obj))
        return obj

    def _arm_motions(self) -> list[ArmMotion]:
        """The moving arms' remaining motions, as the planner reads them."""
        motions = []
        for arm in self._arms.values():
            controller = arm.position_controller
            if not controller.is_moving or controller.trajectory is None:
                continue
            body = arm.body
            motions.append(
                ArmMotion(
                    arm.name,
                    body.body_id,
                    [body.joint_indices[i] for i in arm.kinematics.arm_indices],
                    controller.trajectory.remaining_positions(controller.period),
                    controller.period,
                    {body.link_index(link): link for link in body.link_names},
                    frozenset(fixed_links(body)),
                )
            )
        return motions

    @owning
    def remove_object(self, name: str) -> None:
        """Take object ``name`` out of the world: body, frame, contacts, viewer."""
        self._check_open()
        self._objects.get(name)
        self._tell(lambda listener: listener.on_object_removed(name))
        self._objects.remove(name)
        self._frames.release(FrameOwner.object(name))

    def _check_name_free(self, name: str, used_by: str) -> None:
        if used_by:
            raise NameInUse(name, used_by, list(self._arms), list(self._objects.objects))

    # -- stepping ---------------------------------------------------------------------
    @owning
    def step(self) -> None:
        """Advance one physics step, as ros2_control's loop around the physics.

        Controllers update with the state measured at the current time (read at
        the end of the previous step), torques are written, physics steps, and
        the new state is read, so that :attr:`Arm.positions` and :attr:`tf`
        always describe the world as it is now.
        """
        self._check_open()
        began = time.perf_counter()
        self._requests.drain()
        if self.closed:  # a request closed it
            return
        self._guard.begin_step()  # subscribers run from here on: WorldBusy if they step
        try:
            stamp = self.time
            self._controllers.update(stamp, self._step_index)
            self._memory.write()
            p.stepSimulation(physicsClientId=self._client)
            self._step_index += 1
            self._memory.read()
            self._objects.after_step(self.time)
            self._contacts.scan(self.time)
            self._safety.after_scan()
            if self._step_index % self._status_period_steps == 0:
                for arm in self._arms.values():
                    self._publish_status(arm)
            if self._listeners:
                self._tell(lambda listener: listener.on_step())
        finally:
            self._guard.end_step()
            self._stepping_s += time.perf_counter() - began

    @owning
    def snapshot(self) -> WorldSnapshot:
        """The state of the world now, to :meth:`~WorldSnapshot.restore` later, bit for bit
        (:mod:`armfleet.world.world_snapshot`: what it keeps, and when it refuses).

        Raises:
            UnsavedState: some state is out of reach (a compiled object of an unknown type).
        """
        self._check_open()
        machinery: tuple[object, ...] = (self._models, self._listeners, self._viewer)
        machinery += (self._guard, self._planner, self._planned_moves, self._requests)
        return WorldSnapshot(self, keep=machinery, keep_attributes=("_stepping_s",))

    @property
    def stepping_s(self) -> float:
        """Wall time spent in :meth:`step` since the world was made [s] (the simulation's
        share of a program's time; a sweep's rows report it per run)."""
        return self._stepping_s

    @property
    def safety(self) -> SafetySupervisor:
        """Protective stops: their count, and the contacts excused after a reset."""
        return self._safety

    @property
    def contacts(self) -> ContactMonitor:
        """Contacts of the last step and the running count."""
        return self._contacts

    def _on_contact(self, contact: Contact, deeper: bool) -> None:
        self._safety.on_new_contact(contact, deeper)

    def _publish_status(self, arm: Arm) -> None:
        self._bus.publish(topics.status(arm.name), arm.status(self.time))

    @owning
    def run(
        self,
        duration: float,
        *,
        realtime: bool = False,
        on_step: Callable[[World], None] | None = None,
    ) -> None:
        """Advance ``duration`` seconds of simulated time.

        Args:
            duration: simulated time to advance [s], in [0, 1e6]: longer is a typo.
            realtime: pace the steps to the wall clock instead of running flat out.
            on_step: called after every step (e.g. for logging); it may spawn, remove
                or close (then run returns), as bus subscribers may not.

        Raises:
            WorldBusy: another thread is stepping the world, or run was called from
                inside a step (a bus subscriber).
        """
        duration = RUN_DURATION_S.check(duration, "duration")  # as the CLI's --duration
        realtime = flag(realtime, "realtime")
        if on_step is not None and not callable(on_step):
            raise ArmfleetError(
                f"run: on_step takes a function of the world (or None), "
                f"got {type(on_step).__name__}"
            )
        steps = round(duration / self._dt)
        wall_start, sim_start = time.perf_counter(), self.time
        for _ in range(steps):
            self.step()
            if on_step is not None and not self.closed:
                on_step(self)
            if self._guard.take_close():  # asked from a subscriber or another thread
                self.close()
            if self.closed:
                return
            if realtime:
                ahead = (self.time - sim_start) - (time.perf_counter() - wall_start)
                if ahead > 0.002:
                    time.sleep(ahead)

    # -- lifetime ---------------------------------------------------------------------
    def _arm_states(self) -> dict[str, tuple[ArmKinematics, FloatArray]]:
        return {name: (arm.kinematics, arm.body.position) for name, arm in self._arms.items()}

    def _check_open(self) -> None:
        self._lifetime.check()

    @property
    def closed(self) -> bool:
        return not self._lifetime.alive

    def close(self) -> None:
        """Disconnect the physics engine; the world can no longer be used, nor any
        handle of it (arms, grippers, ``tf``, objects raise :class:`WorldClosed`).

        From inside a step (a bus subscriber) or from another thread while one steps
        the world, the world closes once that step is over (``run`` then returns)."""
        if not self._lifetime.alive:
            return
        with self._guard.closing() as now:
            if not now:  # the stepping thread closes it once the step is over
                return
            try:
                # Last attached first (a Foxglove server before the viewer), while the
                # handles still work: the viewer's refresher thread reads them.
                for listener in reversed(self._listeners):
                    try:
                        listener.on_close()
                    except Exception:
                        logger.exception("front end %s failed to close", type(listener).__name__)
                self._listeners.clear()
            finally:
                self._lifetime.end()
                self._planned_moves.close()
                self._requests.cancel_all(WorldClosed())
                p.disconnect(physicsClientId=self._client)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc: builtins.object) -> None:  # World.object shadows the builtin
        self.close()
