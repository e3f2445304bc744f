"""Keeping a simulation's ROS 2 traffic on this machine (the default).

Fast DDS, ROS 2's default middleware, announces a participant by multicast on every
interface; even ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` leaves it listening on all
of them (it sends only to the loopback, measured with strace). armfleet's participant
instead takes the profile ``fastdds_loopback.xml`` beside this module: UDP bound to
127.0.0.1 plus shared memory, discovery by unicast to the loopback's participant ports,
no multicast. ``ROS_AUTOMATIC_DISCOVERY_RANGE=SYSTEM_DEFAULT`` makes rmw_fastrtps leave
that profile as it is (with LOCALHOST or SUBNET it replaces the transports, or adds the
multicast group to the peers). Nodes on this machine still find the world, whatever
their own range: it announces itself to their loopback ports.

Both are environment variables of the process, read when the participant is created:
a world serving ROS 2 sets them for its whole process.
"""

from __future__ import annotations

import os
from pathlib import Path

#: The Fast DDS profile of a loopback-only participant.
PROFILE = Path(__file__).with_name("fastdds_loopback.xml")


def loopback_environment() -> dict[str, str]:
    """The variables that keep a ROS 2 process's participants on the loopback
    (give them to a ROS 2 node's environment to keep it there too)."""
    return {
        "FASTDDS_DEFAULT_PROFILES_FILE": str(PROFILE),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "SYSTEM_DEFAULT",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    }


def keep_on_loopback() -> None:
    """Set :func:`loopback_environment` in this process, before its first participant."""
    os.environ.update(loopback_environment())
