"""A world served to ROS 2: one rclpy node, ``/armfleet``, with what a ROS 2 user expects
of a simulated ros2_control robot (docs/ros2.md):

- ``/clock`` (``rosgraph_msgs/Clock``) from simulated time; every stamp is simulated time;
- ``/tf`` and ``/tf_static`` (``tf2_msgs/TFMessage``), ``/diagnostics``, ``/collisions``;
- per arm, in its namespace: ``joint_states``, ``robot_description`` (transient local),
  ``joint_trajectory_controller/{follow_joint_trajectory,joint_trajectory}``,
  ``forward_position_controller/commands`` and ``gripper_controller/gripper_cmd``.

The streamed topics go out at ``rate_hz`` instants per simulated second (the bus computes
nothing between two instants). ROS callbacks run in the node's executor threads and act
on the world through ``world.submit``; publishing happens in the stepping thread.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage as RosTFMessage
from visualization_msgs.msg import MarkerArray

from armfleet import topics
from armfleet.checks.number_ranges import DEFAULT_ROS_RATE_HZ, ROS_DOMAIN_ID, ROS_RATE_HZ
from armfleet.errors import ArmfleetError
from armfleet.ros import conversions
from armfleet.ros.cdr import JointStateLayout, TfLayout
from armfleet.ros.demand_stream import DemandStream
from armfleet.ros.errors import RosError
from armfleet.ros.forward_command import ForwardCommand
from armfleet.ros.gripper_action import GripperAction
from armfleet.ros.loopback import keep_on_loopback
from armfleet.ros.status import contact_markers, diagnostics
from armfleet.ros.trajectory_action import TrajectoryAction
from armfleet.ros.trajectory_controller import TrajectoryController
from armfleet.world.world_listener import WorldListener

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.publisher import Publisher

    from armfleet.arms.arm import Arm
    from armfleet.messages import ArmStatus, CollisionReport, TFMessage
    from armfleet.runtime.bus import Subscription
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: The node's name.
NODE_NAME = "armfleet"
#: Instants of the streamed topics per simulated second by default.
DEFAULT_RATE_HZ = DEFAULT_ROS_RATE_HZ
#: Executor threads: goals wait in them while their arm moves.
EXECUTOR_THREADS = 64
#: How long closing waits for the executor's threads [s].
STOP_WAIT_S = 5.0

_LATCHED = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)
_TF = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
_STREAM = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


@dataclass
class _ArmInterfaces:
    """One arm's topics, action servers and bus subscriptions."""

    joint_states: Publisher[JointState]
    description: Publisher[String]
    trajectory: TrajectoryAction
    forward: ForwardCommand
    gripper: GripperAction | None
    joint_stream: DemandStream
    watches: list[Subscription]


class RosServer:
    """Serves a world to ROS 2 (see the module docstring); :func:`serve_ros` starts one.

    Args:
        world: the world; call from the thread that steps it.
        domain_id: the ROS domain (0..232); None: ``ROS_DOMAIN_ID``, or 0.
        localhost_only: keep discovery and traffic on this machine
            (:mod:`armfleet.ros.loopback`); False: the environment's ROS 2 settings rule.
        rate_hz: instants of the streamed topics per simulated second.
    """

    def __init__(
        self,
        world: World,
        domain_id: int | None = None,
        *,
        localhost_only: bool = True,
        rate_hz: float = DEFAULT_RATE_HZ,
    ) -> None:
        if domain_id is not None and not ROS_DOMAIN_ID.contains(domain_id):
            raise RosError(f"ROS domain {domain_id!r} is invalid; give {ROS_DOMAIN_ID.valid}")
        if not ROS_RATE_HZ.contains(rate_hz):
            raise RosError(f"ROS rate {rate_hz!r} is invalid; give {ROS_RATE_HZ.valid}")
        rate = float(rate_hz)
        if world.closed:
            raise RosError("cannot serve a closed world to ROS 2")
        self._world = world
        self._period = 1.0 / rate
        self.rate_hz = rate
        self._closed = False
        self._lock = threading.Lock()
        if localhost_only:
            keep_on_loopback()
        self._context = rclpy.Context()
        rclpy.init(
            context=self._context,
            domain_id=None if domain_id is None else int(domain_id),
            signal_handler_options=SignalHandlerOptions.NO,
        )
        self.domain_id = self._context.get_domain_id()
        self._node: Node = rclpy.create_node(
            NODE_NAME, context=self._context, start_parameter_services=False
        )
        self._group = ReentrantCallbackGroup()
        self._clock = self._node.create_publisher(Clock, "/clock", _STREAM)
        self._tf = self._node.create_publisher(RosTFMessage, "/tf", _TF)
        self._tf_static = self._node.create_publisher(RosTFMessage, "/tf_static", _LATCHED)
        self._diagnostics = self._node.create_publisher(DiagnosticArray, "/diagnostics", _STREAM)
        self._collisions = self._node.create_publisher(MarkerArray, "/collisions", _STREAM)
        self._arms: dict[str, _ArmInterfaces] = {}
        #: Threads taking action servers down once their goals returned (deferred_close).
        self._retiring: list[threading.Thread] = []
        self._tf_layouts: dict[tuple[tuple[str, str], ...], TfLayout] = {}
        self._next_clock = 0.0
        self._tf_stream = DemandStream(world.bus, topics.TF, self._tf, self._tf_bytes, self._period)
        self._watches = [world.bus.subscribe(topics.COLLISIONS, self._on_collisions)]
        self._executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS, context=self._context)
        self._executor.add_node(self._node)
        self._spinner = threading.Thread(
            target=self._spin, name="armfleet-ros-executor", daemon=True
        )
        self._spinner.start()
        self._link = _WorldLink(self)
        try:
            for arm in world.arms.values():
                self._add_arm(arm)
            world.attach(self._link)
        except BaseException:
            self.close()
            raise
        logger.info(
            "ROS 2: node /%s on domain %d%s", NODE_NAME, self.domain_id,
            " (this machine only)" if localhost_only else "",
        )  # fmt: skip

    # -- properties -------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def node_name(self) -> str:
        return f"/{NODE_NAME}"

    @property
    def arms(self) -> tuple[str, ...]:
        """The arms served now."""
        return tuple(self._arms)

    # -- lifetime ---------------------------------------------------------------------
    def close(self) -> None:
        """Stop serving: goals end aborted, the node leaves the ROS graph. Idempotent;
        call it from the thread that steps the world, or once it stopped."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._world.detach(self._link)
        for name in list(self._arms):
            self._remove_arm(name, "the ROS 2 interface closed")
        for watch in self._watches:
            watch.cancel()
        self._tf_stream.close()
        for thread in self._retiring:  # the goals' results go out before the node goes
            thread.join(STOP_WAIT_S)
        self._executor.shutdown(timeout_sec=STOP_WAIT_S)
        self._spinner.join(STOP_WAIT_S)
        self._node.destroy_node()
        self._context.try_shutdown()

    def __enter__(self) -> RosServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else f"domain {self.domain_id}"
        return f"RosServer({state}, {len(self._arms)} arms)"

    # -- stepping thread --------------------------------------------------------------
    def _on_step(self) -> None:
        now = self._world.time
        if now + 1e-12 >= self._next_clock:
            self._next_clock = now + self._period
            self._clock.publish(Clock(clock=conversions.ros_time(now)))
            self._tf_stream.refresh()  # streams start and stop with their subscribers
            for interfaces in self._arms.values():
                interfaces.joint_stream.refresh()
        for interfaces in self._arms.values():
            if interfaces.trajectory.busy:
                interfaces.trajectory.on_step(now)

    def _add_arm(self, arm: Arm) -> None:
        node, bus, name = self._node, self._world.bus, arm.name
        controller = TrajectoryController(arm)
        joint_states = node.create_publisher(JointState, f"/{name}/joint_states", _STREAM)
        description = node.create_publisher(String, f"/{name}/robot_description", _LATCHED)
        layout = JointStateLayout(arm.joint_state.name)
        interfaces = _ArmInterfaces(
            joint_states,
            description,
            TrajectoryAction(node, self._world, controller, self._period),
            ForwardCommand(node, self._world, arm, self._group),
            GripperAction(node, self._world, arm, self._group) if arm.has_gripper else None,
            DemandStream(
                bus, topics.joint_states(name), joint_states, layout.serialize, self._period
            ),
            [bus.subscribe(topics.status(name), self._on_status)],
        )
        self._arms[name] = interfaces
        interfaces.joint_stream.refresh()
        description.publish(String(data=arm.description.urdf))
        self._publish_static()

    def _remove_arm(self, name: str, reason: str) -> None:
        interfaces = self._arms.pop(name, None)
        if interfaces is None:
            return
        for watch in interfaces.watches:
            watch.cancel()
        interfaces.joint_stream.close()
        interfaces.trajectory.close_goals(reason)
        self._retiring = [thread for thread in self._retiring if thread.is_alive()]
        self._retiring.append(interfaces.trajectory.close())
        interfaces.forward.close()
        if interfaces.gripper is not None:
            self._retiring.append(interfaces.gripper.close())
        self._node.destroy_publisher(interfaces.joint_states)
        self._node.destroy_publisher(interfaces.description)
        self._publish_static()

    def _publish_static(self) -> None:
        """Every arm's fixed transforms in one latched message, as a static broadcaster
        that holds them all (a late subscriber gets the whole set)."""
        static = [
            t for message in self._world.bus.latched(topics.TF_STATIC) for t in message.transforms
        ]
        self._tf_static.publish(conversions.tf_message(static))

    def _tf_bytes(self, message: TFMessage) -> bytes:
        frames = tuple((t.frame_id, t.child_frame_id) for t in message.transforms)
        layout = self._tf_layouts.get(frames)
        if layout is None:
            layout = self._tf_layouts[frames] = TfLayout(frames)
        return layout.serialize(message)

    def _on_status(self, status: ArmStatus) -> None:
        self._diagnostics.publish(diagnostics(status))

    def _on_collisions(self, report: CollisionReport) -> None:
        self._collisions.publish(contact_markers(report))

    # -- executor thread --------------------------------------------------------------
    def _spin(self) -> None:
        try:
            self._executor.spin()
        except Exception:  # the context shut down under it
            if not self._closed:
                logger.exception("ROS 2: the executor stopped")


class _WorldLink(WorldListener):
    def __init__(self, server: RosServer) -> None:
        self._server = server

    def on_arm_ready(self, arm: Arm) -> None:
        self._server._add_arm(arm)

    def on_arm_removed(self, name: str) -> None:
        self._server._remove_arm(name, f"{name} was removed from the world")

    def on_step(self) -> None:
        self._server._on_step()

    def on_close(self) -> None:
        self._server.close()


def serve_ros(
    world: World,
    domain_id: int | None = None,
    *,
    localhost_only: bool = True,
    rate_hz: float = DEFAULT_RATE_HZ,
) -> RosServer:
    """Serve ``world`` to ROS 2; see :class:`RosServer`. Close it when done."""
    try:
        return RosServer(world, domain_id, localhost_only=localhost_only, rate_hz=rate_hz)
    except ArmfleetError:
        raise
    except Exception as exc:  # rclpy's own failures (RCLError, RuntimeError)
        raise RosError(f"cannot start ROS 2: {exc}") from None
