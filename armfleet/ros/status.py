"""Arm status and contacts in ROS 2's standard messages.

- Each arm's ``/<arm>/status`` becomes a ``diagnostic_msgs/DiagnosticStatus`` on
  ``/diagnostics`` (what ros2_control's hardware and rqt_robot_monitor use): level OK
  while holding or moving, WARN in a protective stop, ERROR in a fault; the mode and
  reason in the message, the mode and the effort-limit hits as values.
- ``/collisions`` has no standard message type in ROS 2's common interfaces: each report
  becomes a ``visualization_msgs/MarkerArray`` (what RViz draws), a sphere per contact
  at its point in ``world``, sized by the depth, with the two bodies and links as the
  marker's ``text`` (``body_a/link_a|body_b/link_b``); the first marker deletes the
  previous report's.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from visualization_msgs.msg import Marker, MarkerArray

from armfleet.messages import ArmMode, ArmStatus, CollisionReport
from armfleet.ros.conversions import ros_time

_LEVELS = {
    ArmMode.HOLDING: DiagnosticStatus.OK,
    ArmMode.MOVING: DiagnosticStatus.OK,
    ArmMode.PROTECTIVE_STOP: DiagnosticStatus.WARN,
    ArmMode.ERROR: DiagnosticStatus.ERROR,
}
#: Smallest sphere drawn for a contact [m].
MARKER_MIN_M = 0.01


def diagnostics(status: ArmStatus) -> DiagnosticArray:
    """``/diagnostics`` message of one arm's status."""
    message = DiagnosticArray()
    message.header.stamp = ros_time(status.stamp)
    text = status.mode.value if not status.reason else f"{status.mode.value}: {status.reason}"
    message.status = [
        DiagnosticStatus(
            level=_LEVELS[status.mode],
            name=f"{status.arm}: arm",
            message=text,
            hardware_id=status.arm,
            values=[
                KeyValue(key="mode", value=status.mode.value),
                KeyValue(key="reason", value=status.reason),
                KeyValue(
                    key="effort_limit_hits",
                    value=" ".join(str(steps) for steps in status.saturation_steps),
                ),
            ],
        )
    ]
    return message


def contact_markers(report: CollisionReport) -> MarkerArray:
    """``/collisions`` message of one contact report."""
    stamp = ros_time(report.stamp)
    clear = Marker(action=Marker.DELETEALL, ns="contacts")
    clear.header.stamp, clear.header.frame_id = stamp, "world"
    markers = [clear]
    for index, contact in enumerate(report.contacts):
        marker = Marker(ns="contacts", id=index, type=Marker.SPHERE, action=Marker.ADD)
        marker.header.stamp, marker.header.frame_id = stamp, "world"
        x, y, z = contact.position
        marker.pose.position.x, marker.pose.position.y, marker.pose.position.z = x, y, z
        marker.pose.orientation.w = 1.0
        size = max(MARKER_MIN_M, 2.0 * abs(contact.depth))
        marker.scale.x = marker.scale.y = marker.scale.z = size
        marker.color.r, marker.color.a = 1.0, 0.8
        marker.text = f"{contact.body_a}/{contact.link_a}|{contact.body_b}/{contact.link_b}"
        markers.append(marker)
    return MarkerArray(markers=markers)
