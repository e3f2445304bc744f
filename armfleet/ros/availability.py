"""Whether ROS 2 is installed for armfleet: rclpy and its messages from the ``ros``
extra, and the two interface packages built from ``ros_interfaces/``."""

from __future__ import annotations

from importlib.util import find_spec

from armfleet.checks.extras import require_extra
from armfleet.errors import ArmfleetError, MissingExtra

#: What builds the interface packages the package index lacks.
BUILD_COMMAND = (
    "pip install --no-build-isolation ./ros_interfaces/tf2_msgs ./ros_interfaces/control_msgs"
)


class MissingRosInterfaces(MissingExtra):
    """rclpy is there, but not an interface package built from ``ros_interfaces/``."""

    def __init__(self, package: str) -> None:
        self.feature, self.extra, self.missing = "ROS 2", "ros", package
        ArmfleetError.__init__(
            self,
            f"ROS 2 needs {package}, built from armfleet's ros_interfaces/: {BUILD_COMMAND} "
            "(after pip install 'armfleet[ros]'; docs/ros2.md)",
        )


def require_ros() -> None:
    """Raise a one-line error naming the install command unless ROS 2 can be served."""
    require_extra("ROS 2", "ros", "rclpy", "sensor_msgs", "trajectory_msgs", "rosgraph_msgs")
    for package in ("tf2_msgs", "control_msgs"):
        try:
            found = find_spec(package) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            raise MissingRosInterfaces(package)
