"""Errors of the live world API, all :class:`~armfleet.errors.ArmfleetError` s."""

from __future__ import annotations

from armfleet.errors import ArmfleetError


class ProtocolError(ArmfleetError):
    """A request the server cannot read: not msgpack, wrong shape, wrong types, too big."""


class UnknownService(ProtocolError):
    def __init__(self, name: str, available: list[str]) -> None:
        self.name = name
        super().__init__(f"unknown service {name!r}; services: {', '.join(sorted(available))}")


class UnknownTopic(ArmfleetError):
    def __init__(self, topic: str, available: list[str]) -> None:
        self.topic = topic
        listed = ", ".join(sorted(available)) or "(none)"
        super().__init__(f"unknown topic {topic!r}; topics: {listed}")


class RemoteError(ArmfleetError):
    """An error the world reported for a request (its message is the world's own).

    Attributes:
        kind: the name of the error in the world (``UnknownArm``, ``JointLimitError``...).
    """

    def __init__(self, kind: str, message: str) -> None:
        self.kind = kind
        super().__init__(message)


class NoWorldFound(ArmfleetError):
    """No running world to connect to, or none answering at the given address."""


class RequestTimeout(ArmfleetError):
    """The world did not answer a request in time."""


class ConnectionLost(ArmfleetError):
    """The world went away (it closed, or stopped answering)."""
