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

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.remote.client import Client, connect
    from armfleet.remote.client_quotas import ClientQuotas, QuotaExceeded
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

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Client": "armfleet.remote.client",
        "connect": "armfleet.remote.client",
        "ClientQuotas": "armfleet.remote.client_quotas",
        "QuotaExceeded": "armfleet.remote.client_quotas",
        "RemoteArm": "armfleet.remote.remote_arm",
        "RemoteGripper": "armfleet.remote.remote_gripper",
        "RemoteSubscription": "armfleet.remote.remote_subscription",
        "WorldServer": "armfleet.remote.server",
        "serve": "armfleet.remote.server",
        "ObjectInfo": "armfleet.remote.world_info",
        "TopicInfo": "armfleet.remote.world_info",
        "WorldInfo": "armfleet.remote.world_info",
        "ConnectionLost": "armfleet.services.errors",
        "NoWorldFound": "armfleet.services.errors",
        "ProtocolError": "armfleet.services.errors",
        "RemoteError": "armfleet.services.errors",
        "RemotePlanningFailed": "armfleet.services.errors",
        "RequestTimeout": "armfleet.services.errors",
        "TooManyRequests": "armfleet.services.errors",
        "TopicGone": "armfleet.services.errors",
        "UnknownTopic": "armfleet.services.errors",
        "RunState": "armfleet.services.run_state",
    },
)

__all__ = [
    "Client",
    "ClientQuotas",
    "ConnectionLost",
    "NoWorldFound",
    "ObjectInfo",
    "ProtocolError",
    "QuotaExceeded",
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
