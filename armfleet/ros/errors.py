"""The ROS 2 interface's errors."""

from __future__ import annotations

from armfleet.errors import ArmfleetError


class RosError(ArmfleetError):
    """The ROS 2 interface cannot start as asked (bad domain or rate, closed world)."""
