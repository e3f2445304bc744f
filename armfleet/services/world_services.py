"""What each request does to the world.

Every ``prepare_*`` runs in the server thread: it checks the request's fields
and returns a function for the stepping thread, which alone touches the world.
So checks that need only the request fail at once, and the world sees only
well-formed work. Errors the world raises (unknown arm, NaN target, joint limit)
are its own, with its own messages.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

from armfleet.arms.arm import Arm
from armfleet.checks.number_ranges import STEP_COUNT
from armfleet.description.model_options import SETTING_KEYS, parse_model_options
from armfleet.errors import ArmFault, ArmfleetError, ProtectiveStopError
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.messages import ArmMode, JointCommand
from armfleet.runtime.bus import Subscription
from armfleet.services.arguments import Arguments
from armfleet.services.codec import to_wire
from armfleet.services.errors import UnknownService, UnknownTopic
from armfleet.services.manipulation_services import ManipulationServices, describe_gripper
from armfleet.services.model_file_access import require_readable_model_files
from armfleet.services.object_services import ObjectServices
from armfleet.services.planned_move import planned_move
from armfleet.services.planning_options import PLANNING_FIELDS, PlanningOptions
from armfleet.services.protocol import Service, armfleet_version
from armfleet.services.run_state import RunState
from armfleet.services.subscription_queue import SubscriptionQueue
from armfleet.spec import ArmSpec, ControllerConfig
from armfleet.world import World
from armfleet.world.launch import spawn_from_spec

Work = Callable[[], Any]

#: Fields each service accepts in ``args``.
FIELDS: dict[Service, tuple[str, ...]] = {
    Service.HELLO: ("protocol", "client"),
    Service.ATTACH: (),
    Service.DETACH: ("stream",),
    Service.INFO: (),
    Service.ARMS: (),
    Service.ARM: ("name",),
    Service.JOINT_STATE: ("name",),
    Service.LOOKUP: ("target", "source"),
    Service.SPAWN: ("name", "model", "at", "initial_positions", "parameters", *SETTING_KEYS),
    Service.REMOVE: ("name",),
    Service.MOVE: ("name", "positions", *PLANNING_FIELDS),
    Service.MOVE_POSE: ("name", "pose", "position", "frame", "link", "linear", *PLANNING_FIELDS),
    Service.MOVE_TOGETHER: ("targets", *PLANNING_FIELDS),
    Service.GRIP: ("name", "action", "width", "force"),
    Service.WAIT: ("name", "timeout_s", "gripper"),
    Service.RESET: ("name", "stop_only"),
    Service.TOPICS: (),
    Service.SUBSCRIBE: ("topic", "stream", "sub", "rate_hz", "queue_size"),
    Service.UNSUBSCRIBE: ("stream", "sub"),
    Service.PUBLISH: ("topic", "message"),
    Service.PAUSE: (),
    Service.RESUME: (),
    Service.STEP: ("count",),
    Service.OBJECTS: (),
    Service.ADD_OBJECT: ("name", "shape", "size", "mass", "friction", "color", "at", "rpy_deg"),
    Service.REMOVE_OBJECT: ("name",),
}
#: Simulated time an arm may take to settle on its target once its motion ended [s].
SETTLE_S = 0.5
_POSE_KEYS = ("x", "y", "z", "yaw_deg", "roll_deg", "pitch_deg")


class WorldServices:
    """The services of one world.

    Args:
        world: the world served.
        run_state: its loop's run control; without one, pause/resume/step are refused.
        address: the API address (reported by ``info``).
    """

    def __init__(self, world: World, run_state: RunState | None, address: str) -> None:
        self._world = world
        self._run_state = run_state
        self.address = address
        manipulation, objects = ManipulationServices(world), ObjectServices(world)
        #: ``wait``'s check for a gripper (the arm's is :meth:`wait_check`).
        self.gripper_wait_check = manipulation.gripper_wait_check
        self._plain: dict[Service, Callable[[Arguments], Work]] = {
            Service.INFO: self.prepare_info,
            Service.ARMS: self.prepare_arms,
            Service.ARM: self.prepare_arm,
            Service.JOINT_STATE: self.prepare_joint_state,
            Service.LOOKUP: self.prepare_lookup,
            Service.SPAWN: self.prepare_spawn,
            Service.REMOVE: self.prepare_remove,
            Service.MOVE: self.prepare_move,
            Service.MOVE_POSE: manipulation.prepare_move_pose,
            Service.MOVE_TOGETHER: manipulation.prepare_move_together,
            Service.GRIP: manipulation.prepare_grip,
            Service.RESET: self.prepare_reset,
            Service.TOPICS: self.prepare_topics,
            Service.PUBLISH: self.prepare_publish,
            Service.PAUSE: self.prepare_pause,
            Service.RESUME: self.prepare_resume,
            Service.STEP: self.prepare_step,
            Service.OBJECTS: objects.prepare_objects,
            Service.ADD_OBJECT: objects.prepare_add_object,
            Service.REMOVE_OBJECT: objects.prepare_remove_object,
        }

    def prepare(self, service: Service, args: Arguments) -> Work | None:
        """The work of a plain service (None for those the server handles itself)."""
        prepare = self._plain.get(service)
        return prepare(args) if prepare is not None else None

    # -- reading ----------------------------------------------------------------------
    def prepare_info(self, args: Arguments) -> Work:
        world, run_state = self._world, self._run_state

        def info() -> dict[str, Any]:
            return {
                "time_s": world.time,
                "dt_s": world.dt,
                "realtime_factor": None if run_state is None else run_state.realtime_factor,
                "paused": run_state is not None and run_state.paused,
                "arms": list(world.arms),
                "version": armfleet_version(),
                "address": self.address,
            }

        return info

    def prepare_arms(self, args: Arguments) -> Work:
        world = self._world
        return lambda: [describe_arm(world, arm) for arm in world.arms.values()]

    def prepare_arm(self, args: Arguments) -> Work:
        name, world = args.text("name"), self._world
        return lambda: describe_arm(world, world.arm(name))

    def prepare_joint_state(self, args: Arguments) -> Work:
        name, world = args.text("name"), self._world
        return lambda: to_wire(world.arm(name).joint_state)

    def prepare_lookup(self, args: Arguments) -> Work:
        target, source, world = args.text("target"), args.text("source"), self._world

        def lookup() -> dict[str, Any]:
            matrix = world.tf.lookup(target, source)
            return {"time_s": world.time, "matrix": to_wire(matrix.reshape(-1))}

        return lookup

    def prepare_topics(self, args: Arguments) -> Work:
        world = self._world

        def topics() -> list[dict[str, Any]]:
            return [
                {"topic": topic, "type": kind.__name__, "command": kind is JointCommand}
                for topic, kind in sorted(world.bus.topics.items())
            ]

        return topics

    # -- arms -------------------------------------------------------------------------
    def prepare_spawn(self, args: Arguments) -> Work:
        """A model file (and an end effector's) is read by this process, the world's: its
        path must be one this process can read (the client makes a relative path absolute
        on its side), else :class:`~armfleet.services.errors.ModelFileUnreadable` says
        so before the world is touched. The model's settings are the fields of
        :data:`~armfleet.description.model_options.SETTING_KEYS`."""
        initial = args.vector("initial_positions", None)
        settings = {key: args.raw(key) for key in SETTING_KEYS if args.has(key)}
        spec = ArmSpec(
            args.text("name"),
            args.text("model", "panda"),
            _pose(args),
            None if initial is None else tuple(initial),
            _controllers(args),
            parse_model_options(settings, "spawn"),
        )
        require_readable_model_files(spec.model, spec.options)  # the world untouched
        world = self._world

        def spawn() -> dict[str, Any]:
            return describe_arm(world, spawn_from_spec(world, spec))

        return spawn

    def prepare_remove(self, args: Arguments) -> Work:
        name, world = args.text("name"), self._world

        def remove() -> dict[str, Any]:
            world.remove(name)
            return {"time_s": world.time, "arms": list(world.arms)}

        return remove

    def prepare_move(self, args: Arguments) -> Work:
        """A planned move (``avoid_collisions``) is planned off the stepping thread
        (:func:`~armfleet.services.planning_options.planned_move`); the reply comes when
        the motion starts."""
        name, positions, world = args.text("name"), args.vector("positions"), self._world
        options = PlanningOptions.from_request("move", args).keywords()

        def moved(arm: Arm, duration: float) -> dict[str, Any]:
            return {"time_s": world.time, "duration_s": duration, "moving": arm.is_moving}

        def move() -> Any:
            arm = world.arm(name)
            if options:
                return planned_move(world, {name: positions}, options, partial(moved, arm))
            return moved(arm, arm.move_to(positions))

        return move

    def prepare_reset(self, args: Arguments) -> Work:
        name, stop_only, world = args.text("name"), args.flag("stop_only", False), self._world

        def reset() -> dict[str, Any]:
            arm = world.arm(name)
            if stop_only:
                arm.reset_stop()
            else:
                arm.reset()
            return describe_arm(world, arm)

        return reset

    def wait_check(self, name: str) -> Callable[[], dict[str, Any] | None]:
        """A check, run once per step, of whether ``name`` has finished its motion.

        It returns None while the arm moves, then the arm's state once it holds its
        target (or has had :data:`SETTLE_S` to settle); it raises if the arm stops
        on a contact, faults or leaves the world.
        """
        world = self._world
        settled_since: list[float] = []

        def check() -> dict[str, Any] | None:
            arm = world.arm(name)
            status = arm.status(world.time)
            if status.mode is ArmMode.PROTECTIVE_STOP:
                raise ProtectiveStopError(name, status.reason)
            if status.mode is ArmMode.ERROR:
                raise ArmFault(name, status.reason)
            if arm.is_moving:
                settled_since.clear()
                return None
            if not settled_since:
                settled_since.append(world.time)
            holding = arm.position_controller.is_holding
            if not holding and world.time - settled_since[0] < SETTLE_S:
                return None
            return {
                "time_s": world.time,
                "holding": holding,
                "tracking_error": arm.position_controller.tracking_error,
                "joint_state": to_wire(arm.joint_state),
            }

        return check

    # -- topics -----------------------------------------------------------------------
    def subscribe(
        self, topic: str, queue: SubscriptionQueue
    ) -> Callable[[], tuple[Subscription, str]]:
        """Work that subscribes ``queue`` to ``topic`` (which must exist)."""
        bus = self._world.bus

        def subscribe() -> tuple[Subscription, str]:
            kind = bus.topics.get(topic)
            if kind is None:
                raise UnknownTopic(topic, list(bus.topics))
            return bus.subscribe(topic, queue.push, on_gone=queue.topic_gone), kind.__name__

        return subscribe

    def prepare_publish(self, args: Arguments) -> Work:
        topic = args.text("topic")
        message = Arguments(f"publish {topic}", args.mapping("message"), ("positions",))
        positions = message.vector("positions")
        world = self._world

        def publish() -> dict[str, Any]:
            topics = world.bus.topics
            if topic not in topics:
                raise UnknownTopic(topic, list(topics))
            commands = sorted(t for t, kind in topics.items() if kind is JointCommand)
            if topics[topic] is not JointCommand:
                raise ArmfleetError(
                    f"{topic} carries {topics[topic].__name__}, which the world publishes "
                    f"itself; command topics: {', '.join(commands) or '(none)'}"
                )
            arm = world.arm(topic.split("/")[1])
            arm.move_to(positions)  # the world's checks, then the same message on the topic
            return {"time_s": world.time, "moving": arm.is_moving}

        return publish

    # -- run control ------------------------------------------------------------------
    def _require_run_state(self, what: str) -> RunState:
        if self._run_state is None:
            raise ArmfleetError(f"{what}: this world is stepped by its own program, not paused")
        return self._run_state

    def prepare_pause(self, args: Arguments) -> Work:
        run_state, world = self._require_run_state("pause"), self._world

        def pause() -> dict[str, Any]:
            run_state.pause()
            return {"time_s": world.time, "paused": True}

        return pause

    def prepare_resume(self, args: Arguments) -> Work:
        run_state, world = self._require_run_state("resume"), self._world

        def resume() -> dict[str, Any]:
            run_state.resume()
            return {"time_s": world.time, "paused": False}

        return resume

    def prepare_step(self, args: Arguments) -> Work:
        count = args.in_range("count", 1, STEP_COUNT)
        run_state, world = self._require_run_state("step"), self._world

        def step() -> dict[str, Any]:
            if not run_state.paused:
                raise ArmfleetError("step: the world is running; pause it first")
            for _ in range(count):
                world.step()
            run_state.note_progress(world.time)
            return {"time_s": world.time, "paused": True}

        return step


def describe_arm(world: World, arm: Arm) -> dict[str, Any]:
    """An arm as the ``arms`` and ``arm`` services report it."""
    lower, upper = arm.joint_limits
    status = arm.status(world.time)
    return {
        "name": arm.name,
        "model": arm.model,
        "home": arm.description.home_choice.clause if arm.description.home_choice else "",
        "pose": to_wire(arm.pose),
        "joint_names": list(arm.joint_names),
        "lower": to_wire(lower),
        "upper": to_wire(upper),
        "positions": to_wire(arm.positions),
        "mode": status.mode.value,
        "reason": status.reason,
        "gripper": describe_gripper(arm.gripper, world.time) if arm.has_gripper else None,
    }


def _pose(args: Arguments) -> SpawnPose:
    """``at``: ``[x, y[, z[, yaw_deg]]]`` or a map of :data:`_POSE_KEYS` [m, deg]."""
    if isinstance(args.raw("at"), dict):
        pose = Arguments("spawn", args.raw("at"), _POSE_KEYS, label="'at'")
        # Non-finite values pass here: SpawnPose names the field that is not finite.
        return SpawnPose(**{key: pose.number(key, 0.0, finite=False) for key in _POSE_KEYS})
    return SpawnPose.from_values(args.vector("at", [0.0, 0.0]))


def _controllers(args: Arguments) -> dict[str, ControllerConfig]:
    """``parameters``: per controller, overrides ``{name: number}`` (checked by the world)."""
    controllers: dict[str, ControllerConfig] = {}
    for controller, values in args.mapping("parameters", {}).items():
        label = f"'parameters.{controller}'"
        fields = list(values) if isinstance(values, dict) else []
        checked = Arguments("spawn", values, fields, label=label)
        controllers[controller] = ControllerConfig(
            parameters={key: checked.number(key, finite=False) for key in fields}
        )
    return controllers


def require_known(service: str) -> Service:
    """The :class:`Service` called ``service``, or :class:`UnknownService`."""
    try:
        return Service(service)
    except ValueError:
        raise UnknownService(service, [s.value for s in Service]) from None
