"""Errors of the live world API, all :class:`~armfleet.errors.ArmfleetError` s."""

from __future__ import annotations

import difflib
from typing import Any

from armfleet.errors import ArmfleetError, DescriptionError
from armfleet.planning.failure import FailureReason, PlanningFailed
from armfleet.runtime.bus import TOPIC_PATTERN


class ProtocolError(ArmfleetError):
    """A request the server cannot read: not msgpack, wrong shape, wrong types, too big."""


class UnknownService(ProtocolError):
    def __init__(self, name: str, available: list[str]) -> None:
        self.name = name
        super().__init__(f"unknown service {name!r}; services: {', '.join(sorted(available))}")


class UnknownTopic(ArmfleetError):
    """A topic the world does not have; the message lists them (or, when there are
    many, the ones closest to what was asked)."""

    #: Longest list of topics a message spells out.
    MAX_LISTED = 12

    def __init__(self, topic: str, available: list[str]) -> None:
        self.topic = topic
        self.available = tuple(sorted(available))
        if not TOPIC_PATTERN.match(topic):
            problem = f"topic name {topic!r} is malformed (e.g. /bob/joint_states)"
        else:
            problem = f"unknown topic {topic!r}"
        if len(self.available) <= self.MAX_LISTED:
            choices = f"topics: {', '.join(self.available) or '(none)'}"
        else:
            close = difflib.get_close_matches(topic, self.available, n=3, cutoff=0.6)
            hint = f"did you mean {' or '.join(close)}? " if close else ""
            choices = f"{hint}{len(self.available)} topics: see 'armfleet topic list'"
        super().__init__(f"{problem}; {choices}")


class RemoteError(ArmfleetError):
    """An error the world reported for a request (its message is the world's own).

    Attributes:
        kind: the name of the error in the world (``UnknownArm``, ``JointLimitError``...).
    """

    def __init__(self, kind: str, message: str) -> None:
        self.kind = kind
        super().__init__(message)


class RemotePlanningFailed(RemoteError, PlanningFailed):
    """A :class:`~armfleet.planning.PlanningFailed` the world reported for a request: no
    collision-free motion was planned and nothing moved. ``except PlanningFailed`` catches
    it as it catches the local one; its message is the world's one line.

    Attributes:
        reason, arms, links, samples, blocking_arm: as in the world's error
            (``problem`` stays in the world: None).
    """

    def __init__(self, message: str, fields: dict[str, Any]) -> None:
        # Not PlanningFailed.__init__, which composes a message: this one is the world's.
        ArmfleetError.__init__(self, message)
        self.kind = PlanningFailed.__name__
        self.reason = FailureReason(fields["reason"])
        self.arms = tuple(str(arm) for arm in fields.get("arms", ()))
        links = tuple(str(link) for link in fields.get("links", ()))
        self.links = (links[0], links[1]) if len(links) == 2 else ()
        self.samples = int(fields.get("samples", 0))
        blocking = fields.get("blocking_arm")
        self.blocking_arm = None if blocking is None else str(blocking)
        self.problem = None


def error_fields(error: ArmfleetError) -> dict[str, Any] | None:
    """What a client needs, beyond the type and message, to raise ``error`` again on its
    side (None for errors that are their message)."""
    if isinstance(error, PlanningFailed):
        return {
            "reason": error.reason.value,
            "arms": list(error.arms),
            "links": list(error.links),
            "samples": error.samples,
            "blocking_arm": error.blocking_arm,
        }
    return None


def remote_error(kind: str, message: str, fields: Any) -> RemoteError:
    """The client's error for an error reply: a :class:`RemotePlanningFailed` for a
    ``PlanningFailed`` that came with its fields, else a :class:`RemoteError`."""
    if kind == PlanningFailed.__name__ and isinstance(fields, dict):
        try:
            return RemotePlanningFailed(message, fields)
        except (KeyError, ValueError, TypeError):
            pass  # a world speaking other reasons: its message still says it all
    return RemoteError(kind, message)


class NoWorldFound(ArmfleetError):
    """No running world to connect to, or none answering at the given address."""


class RequestTimeout(ArmfleetError):
    """The world did not answer a request in time."""


class TooManyRequests(ArmfleetError):
    """A client has as many requests in flight as it may; this one was refused, unapplied.

    Attributes:
        limit: requests one client may have in flight.
        raised_by: who sets the limit, and how (appended to the message).
    """

    def __init__(self, limit: int, raised_by: str = "") -> None:
        self.limit, self.raised_by = limit, raised_by
        super().__init__(
            f"too many requests in flight from this client (limit {limit}); wait for "
            f"replies before sending more (nothing was applied{'; ' if raised_by else ''}"
            f"{raised_by})"
        )


class ConnectionLost(ArmfleetError):
    """The world went away (it closed, or stopped answering)."""


class TopicGone(ArmfleetError):
    """A subscribed topic went away (e.g. its arm was removed): no more messages come.

    Attributes:
        topic: the topic.
    """

    def __init__(self, topic: str, reason: str) -> None:
        self.topic = topic
        super().__init__(reason if topic in reason else f"topic {topic} is gone: {reason}")


class ModelFileUnreadable(DescriptionError):
    """A model file (or an end effector's) that the process owning the world cannot read:
    the live API's model files are read there, not where the client runs.

    Attributes:
        field: the request's field (``model``, ``end_effector.file``).
        path: the path as the world's process saw it.
        reason: why it cannot be read (``not found``, ``permission denied``...).
        pid, host: the world's process and its machine.
    """

    def __init__(self, field: str, path: str, reason: str, pid: int, host: str) -> None:
        self.field, self.path, self.reason, self.pid, self.host = field, path, reason, pid, host
        super().__init__(
            f"{field} {path!r}, as the process that owns the world (process {pid} on {host}) "
            f"sees it: {reason}; that process reads model files, not the client: give a path "
            "it can read, or a shipped model (armfleet models)"
        )
