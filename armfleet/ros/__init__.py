"""ROS 2: a world served to real ROS 2 nodes (``armfleet[ros]``; docs/ros2.md).

``world.serve_ros()`` (or ``armfleet spawn ... --ros``) starts one rclpy node with the
topics, actions and message types of a simulated ros2_control robot: ``/clock``,
``/tf``, ``/tf_static``, and per arm ``joint_states``, ``robot_description``,
joint_trajectory_controller's ``follow_joint_trajectory`` action and
``joint_trajectory`` topic, ``forward_position_controller/commands`` and the gripper's
``GripperCommand`` action. Discovery and traffic stay on this machine by default.

Rule: a front end (the ``ros`` extra, plus ``tf2_msgs`` and ``control_msgs`` built from
``ros_interfaces/``); attaches to the world as a :class:`~armfleet.world.WorldListener`;
imports the core below.
"""

from __future__ import annotations

from armfleet.ros.availability import require_ros

require_ros()

from armfleet.ros.errors import RosError
from armfleet.ros.loopback import loopback_environment
from armfleet.ros.server import DEFAULT_RATE_HZ, RosServer, serve_ros

__all__ = ["DEFAULT_RATE_HZ", "RosError", "RosServer", "loopback_environment", "serve_ros"]
