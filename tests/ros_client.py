"""A real ROS 2 node (rclpy) that the ROS tests run as a subprocess: it talks to an
armfleet world the way a user's node would and prints what it saw as one JSON line.

    python tests/ros_client.py DOMAIN COMMAND JSON

Commands (JSON holds their arguments):
- ``watch``: ``{"arm", "seconds"}``: joint states, clock, /tf and /tf_static,
  robot_description;
- ``goal``: ``{"arm", "goals": [{"trajectory", "path_tolerance"?, "goal_tolerance"?,
  "goal_time_tolerance"?, "after"?}], "cancel_after"?}``: FollowJointTrajectory goals, the
  later ones sent ``after`` seconds after the first; each one's status, code and text;
- ``publish``: ``{"arm", "trajectory"}``: one message on the joint_trajectory topic;
- ``forward``: ``{"arm", "values"}``: one message on forward_position_controller/commands;
- ``gripper``: ``{"arm", "position", "max_effort"}``: a GripperCommand goal;
- ``monitor``: ``{"arm", "level"}``: ``/diagnostics`` and ``/collisions`` until the arm's
  status reaches ``level`` (0 OK, 1 WARN, 2 ERROR): its statuses and the contacts seen
  (it prints ``listening`` once the arm's first status arrived);
- ``graph``: ``{"arm", "topics"}``: each topic's publishers as ``ros2 topic info
  --verbose`` shows them: node, type and type hash.

A trajectory is ``{"joint_names", "points": [{"positions", "velocities"?,
"accelerations"?, "time_from_start"}], "stamp"?}`` (times in seconds).
"""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Any

import rclpy
from builtin_interfaces.msg import Duration, Time
from control_msgs.action import FollowJointTrajectory, GripperCommand
from control_msgs.msg import JointTolerance
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.action.client import ActionClient
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, String
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import Marker, MarkerArray

#: Longest wait for the world to be discovered or a goal to end [s].
WAIT_S = 60.0
LATCHED = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)


def _duration(seconds: float) -> Duration:
    whole = math.floor(seconds)
    return Duration(sec=int(whole), nanosec=round((seconds - whole) * 1e9))


def _trajectory(spec: dict[str, Any]) -> JointTrajectory:
    message = JointTrajectory(joint_names=list(spec["joint_names"]))
    stamp = float(spec.get("stamp", 0.0))
    whole = math.floor(stamp)
    message.header.stamp = Time(sec=int(whole), nanosec=round((stamp - whole) * 1e9))
    for point in spec["points"]:
        message.points.append(
            JointTrajectoryPoint(
                positions=[float(v) for v in point["positions"]],
                velocities=[float(v) for v in point.get("velocities", [])],
                accelerations=[float(v) for v in point.get("accelerations", [])],
                time_from_start=_duration(float(point["time_from_start"])),
            )
        )
    return message


def _tolerances(given: list[dict[str, Any]]) -> list[JointTolerance]:
    return [JointTolerance(name=t["name"], position=float(t.get("position", 0.0))) for t in given]


class Client:
    def __init__(self, domain: int) -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node("armfleet_test_client", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_until(self, condition: Any, timeout: float = WAIT_S) -> bool:
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.05)
        return True

    def wait_future(self, future: Any, timeout: float = WAIT_S) -> Any:
        if not self.spin_until(future.done, timeout):
            raise SystemExit(f"timed out after {timeout} s")
        return future.result()

    def close(self) -> None:
        self.node.destroy_node()
        self.context.try_shutdown()


def watch(client: Client, arm: str, seconds: float) -> dict[str, Any]:
    node = client.node
    states: list[JointState] = []
    clocks: list[float] = []
    tf: dict[str, Any] = {}
    static: dict[str, Any] = {}
    description: list[str] = []

    def on_tf(message: TFMessage, into: dict[str, Any]) -> None:
        for t in message.transforms:
            r, p = t.transform.rotation, t.transform.translation
            into[t.child_frame_id] = {
                "parent": t.header.frame_id,
                "stamp": t.header.stamp.sec + t.header.stamp.nanosec * 1e-9,
                "translation": [p.x, p.y, p.z],
                "rotation": [r.x, r.y, r.z, r.w],
            }

    node.create_subscription(JointState, f"/{arm}/joint_states", states.append, 10)
    node.create_subscription(
        Clock, "/clock", lambda m: clocks.append(m.clock.sec + m.clock.nanosec * 1e-9), 10
    )
    node.create_subscription(TFMessage, "/tf", lambda m: on_tf(m, tf), 100)
    node.create_subscription(TFMessage, "/tf_static", lambda m: on_tf(m, static), LATCHED)
    node.create_subscription(
        String, f"/{arm}/robot_description", lambda m: description.append(m.data), LATCHED
    )
    client.spin_until(lambda: states and clocks and tf and static and description)
    end = time.monotonic() + seconds
    client.spin_until(lambda: time.monotonic() > end, seconds + 1)
    last = states[-1]
    return {
        "joint_state": {
            "stamp": last.header.stamp.sec + last.header.stamp.nanosec * 1e-9,
            "name": list(last.name),
            "position": list(last.position),
            "velocity": list(last.velocity),
        },
        "clocks": clocks,
        "clock_when_state": clocks[-1],
        "joint_state_count": len(states),
        "tf": tf,
        "tf_static": static,
        "robot_description": description[-1],
    }


def goals(client: Client, arm: str, specs: list[dict[str, Any]], cancel_after: float | None) -> Any:
    action: ActionClient[Any, Any, Any] = ActionClient(
        client.node,
        FollowJointTrajectory,
        f"/{arm}/joint_trajectory_controller/follow_joint_trajectory",
    )
    if not action.wait_for_server(timeout_sec=WAIT_S):
        raise SystemExit("no follow_joint_trajectory server")
    feedback: list[int] = [0] * len(specs)
    handles = []
    started = time.monotonic()
    for index, spec in enumerate(specs):
        after = float(spec.get("after", 0.0))
        client.spin_until(lambda after=after: time.monotonic() - started >= after, after + 1)
        goal = FollowJointTrajectory.Goal(trajectory=_trajectory(spec["trajectory"]))
        goal.path_tolerance = _tolerances(spec.get("path_tolerance", []))
        goal.goal_tolerance = _tolerances(spec.get("goal_tolerance", []))
        goal.goal_time_tolerance = _duration(float(spec.get("goal_time_tolerance", 0.0)))

        def count(_message: Any, index: int = index) -> None:
            feedback[index] += 1

        handle = client.wait_future(action.send_goal_async(goal, feedback_callback=count))
        handles.append(handle)
    if cancel_after is not None:
        client.spin_until(lambda: time.monotonic() - started >= cancel_after, cancel_after + 1)
        client.wait_future(handles[-1].cancel_goal_async())
    results = []
    for index, handle in enumerate(handles):
        response = client.wait_future(handle.get_result_async())
        results.append(
            {
                "accepted": bool(handle.accepted),
                "status": int(response.status),
                "error_code": int(response.result.error_code),
                "error_string": response.result.error_string,
                "feedback": feedback[index],
            }
        )
    return results


def publish(client: Client, topic: str, message_type: Any, message: Any) -> dict[str, Any]:
    publisher = client.node.create_publisher(message_type, topic, 10)
    if not client.spin_until(lambda: publisher.get_subscription_count() > 0):
        raise SystemExit(f"nobody subscribes to {topic}")
    publisher.publish(message)
    end = time.monotonic() + 1.0  # let it go out before the node leaves
    client.spin_until(lambda: time.monotonic() > end, 2.0)
    return {"published": topic}


def gripper(client: Client, arm: str, position: float, max_effort: float) -> dict[str, Any]:
    action: ActionClient[Any, Any, Any] = ActionClient(
        client.node, GripperCommand, f"/{arm}/gripper_controller/gripper_cmd"
    )
    if not action.wait_for_server(timeout_sec=WAIT_S):
        raise SystemExit("no gripper_cmd server")
    goal = GripperCommand.Goal()
    goal.command.position, goal.command.max_effort = position, max_effort
    handle = client.wait_future(action.send_goal_async(goal))
    response = client.wait_future(handle.get_result_async())
    result = response.result
    return {
        "status": int(response.status),
        "position": result.position,
        "stalled": bool(result.stalled),
        "reached_goal": bool(result.reached_goal),
    }


def graph(client: Client, topics: list[str]) -> dict[str, Any]:
    node = client.node

    def publishers(topic: str) -> list[Any]:
        return list(node.get_publishers_info_by_topic(topic))

    def named(topic: str) -> bool:  # node names arrive after the endpoints
        found = publishers(topic)
        return bool(found) and all(not i.node_name.startswith("_NODE_NAME") for i in found)

    client.spin_until(lambda: all(named(topic) for topic in topics))
    return {
        topic: [
            {
                "node": info.node_name,
                "type": info.topic_type,
                "hash": _hash_text(info.topic_type_hash),
            }
            for info in publishers(topic)
        ]
        for topic in topics
    }


def monitor(client: Client, arm: str, level: int) -> dict[str, Any]:
    statuses: list[Any] = []
    contacts: set[str] = set()

    def on_diagnostics(message: DiagnosticArray) -> None:
        statuses.extend(s for s in message.status if s.hardware_id == arm)

    def on_markers(message: MarkerArray) -> None:
        contacts.update(m.text for m in message.markers if m.action == Marker.ADD)

    client.node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
    client.node.create_subscription(MarkerArray, "/collisions", on_markers, 50)
    client.spin_until(lambda: bool(statuses))  # discovered: the arm's statuses arrive
    print("listening", flush=True)
    client.spin_until(lambda: any(int.from_bytes(s.level, "little") >= level for s in statuses))
    return {
        "statuses": [
            {
                "level": int.from_bytes(s.level, "little"),
                "name": s.name,
                "message": s.message,
                "values": {kv.key: kv.value for kv in s.values},
            }
            for s in statuses
        ],
        "contacts": sorted(contacts),
    }


def _hash_text(hashed: Any) -> str:
    """A type hash as ROS 2's tools print it: ``RIHS01_<hex>``."""
    return f"RIHS{hashed.version:02d}_{hashed.value.hex()}"


def main() -> None:
    domain, command, arguments = int(sys.argv[1]), sys.argv[2], json.loads(sys.argv[3])
    client = Client(domain)
    try:
        arm = arguments["arm"]
        if command == "watch":
            out: Any = watch(client, arm, float(arguments.get("seconds", 0.5)))
        elif command == "goal":
            out = goals(client, arm, arguments["goals"], arguments.get("cancel_after"))
        elif command == "publish":
            topic = f"/{arm}/joint_trajectory_controller/joint_trajectory"
            out = publish(client, topic, JointTrajectory, _trajectory(arguments["trajectory"]))
        elif command == "forward":
            topic = f"/{arm}/forward_position_controller/commands"
            message = Float64MultiArray(data=[float(v) for v in arguments["values"]])
            out = publish(client, topic, Float64MultiArray, message)
        elif command == "gripper":
            out = gripper(client, arm, arguments["position"], arguments["max_effort"])
        elif command == "monitor":
            out = monitor(client, arm, int(arguments["level"]))
        elif command == "graph":
            out = graph(client, arguments["topics"])
        else:
            raise SystemExit(f"unknown command {command}")
        print(json.dumps(out), flush=True)
    finally:
        client.close()


if __name__ == "__main__":
    main()
