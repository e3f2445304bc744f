"""What a client learns about a world and its topics."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class WorldInfo:
    """A running world, as :meth:`Client.info` reports it.

    Attributes:
        time_s: simulated time [s].
        dt_s: physics step [s].
        realtime_factor: simulated over wall time lately (0 when paused; None if unknown).
        paused: whether the world is paused.
        arms: arm names, in bring-up order.
        version: armfleet version of the world.
        address: API address.
        pid: process of the world.
        streams: clients receiving topics.
        subscriptions: their subscriptions.
        quotas: what each client, and all clients together, may add, as the world's owner
            set it (the fields of :class:`~armfleet.remote.ClientQuotas`).
    """

    time_s: float
    dt_s: float
    realtime_factor: float | None
    paused: bool
    arms: tuple[str, ...]
    version: str
    address: str
    pid: int
    streams: int
    subscriptions: int
    quotas: dict[str, int] = field(default_factory=dict)

    @classmethod
    def from_wire(cls, data: dict[str, Any]) -> WorldInfo:
        rtf = data.get("realtime_factor")
        return cls(
            time_s=float(data["time_s"]),
            dt_s=float(data["dt_s"]),
            realtime_factor=None if rtf is None else float(rtf),
            paused=bool(data["paused"]),
            arms=tuple(data["arms"]),
            version=str(data["version"]),
            address=str(data["address"]),
            pid=int(data["pid"]),
            streams=int(data.get("streams", 0)),
            subscriptions=int(data.get("subscriptions", 0)),
            quotas={str(key): int(value) for key, value in data.get("quotas", {}).items()},
        )


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a world.

    Attributes:
        topic: its name.
        type_name: its message type (a class of :mod:`armfleet.messages`).
        command: whether clients may publish on it (:meth:`Client.publish`).
    """

    topic: str
    type_name: str
    command: bool


@dataclass(frozen=True)
class ObjectInfo:
    """A scene object of a world, as :meth:`Client.objects` reports it.

    Attributes:
        name: its name, also its frame on ``/tf``.
        shape: ``box``, ``cylinder``, ``sphere`` or ``mesh``.
        size: box (x, y, z) full extents; cylinder (radius, length); sphere (radius,);
            mesh: its bounding box [m].
        mass: [kg]; 0 for a static object.
        static: fixed in the world (mass 0), like a table.
        position: (x, y, z) of its frame in ``world`` now [m].
        rpy_deg: its roll, pitch, yaw now [deg] (R = Rz(yaw) Ry(pitch) Rx(roll)).
    """

    name: str
    shape: str
    size: tuple[float, ...]
    mass: float
    static: bool
    position: tuple[float, float, float]
    rpy_deg: tuple[float, float, float]

    @classmethod
    def from_wire(cls, data: dict[str, Any]) -> ObjectInfo:
        x, y, z = (float(v) for v in data["position"])
        roll, pitch, yaw = (float(v) for v in data["rpy_deg"])
        return cls(
            name=str(data["name"]),
            shape=str(data["shape"]),
            size=tuple(float(v) for v in data["size"]),
            mass=float(data["mass"]),
            static=bool(data["static"]),
            position=(x, y, z),
            rpy_deg=(roll, pitch, yaw),
        )
