"""The live world API: serve a running world over ZeroMQ, command and watch it from elsewhere.

>>> import armfleet
>>> client = armfleet.connect()              # the world `armfleet spawn` started
>>> bob = client.arm("bob")
>>> bob.move_to(bob.positions + 0.2); bob.wait()
>>> client.close()

Rule: a front end (the ZeroMQ transport); imports :mod:`armfleet.services` and
the core below; its handles call the world through the
:class:`~armfleet.remote.service_caller.ServiceCaller` protocol.
"""

from armfleet.remote.client import Client, connect
from armfleet.remote.remote_arm import RemoteArm
from armfleet.remote.remote_gripper import RemoteGripper
from armfleet.remote.remote_subscription import RemoteSubscription
from armfleet.remote.server import WorldServer, serve
from armfleet.remote.world_info import ObjectInfo, TopicInfo, WorldInfo
from armfleet.services.errors import (
    ConnectionLost,
    NoWorldFound,
    ProtocolError,
    RemoteError,
    RemotePlanningFailed,
    RequestTimeout,
    TooManyRequests,
    TopicGone,
    UnknownTopic,
)
from armfleet.services.run_state import RunState

__all__ = [
    "Client",
    "ConnectionLost",
    "NoWorldFound",
    "ObjectInfo",
    "ProtocolError",
    "RemoteArm",
    "RemoteError",
    "RemoteGripper",
    "RemotePlanningFailed",
    "RemoteSubscription",
    "RequestTimeout",
    "RunState",
    "TooManyRequests",
    "TopicGone",
    "TopicInfo",
    "UnknownTopic",
    "WorldInfo",
    "WorldServer",
    "connect",
    "serve",
]
