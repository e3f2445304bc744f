"""In-process publish/subscribe bus with ROS-style topic names.

Callbacks run synchronously in the publishing thread (the one stepping the
world), so the world stays single-threaded and deterministic. Latched topics
(like ROS transient-local ``/tf_static``) replay their messages to late
subscribers.
"""

from __future__ import annotations

import logging
import re
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from armfleet.errors import ArmfleetError

logger = logging.getLogger("armfleet")

Callback = Callable[[Any], None]
TOPIC_PATTERN = re.compile(r"^(/[a-z][a-z0-9_]*)+$")


class TopicError(ArmfleetError):
    """A malformed topic name, or a message of the wrong type for a topic."""


@dataclass(eq=False)
class Subscription:
    """Handle returned by :meth:`Bus.subscribe`; call :meth:`cancel` to stop."""

    topic: str
    callback: Callback
    _bus: Bus | None = field(repr=False, default=None)

    def cancel(self) -> None:
        if self._bus is not None:
            self._bus._remove(self)
            self._bus = None


@dataclass(eq=False)
class Tap:
    """Handle returned by :meth:`Bus.subscribe_all`; call :meth:`cancel` to stop."""

    callback: Callable[[str, Any], None]
    _bus: Bus | None = field(repr=False, default=None)

    def cancel(self) -> None:
        if self._bus is not None and self in self._bus._taps:
            self._bus._taps.remove(self)
        self._bus = None


class Bus:
    """Topics of one world."""

    def __init__(self) -> None:
        self._subscriptions: dict[str, list[Subscription]] = defaultdict(list)
        self._types: dict[str, type] = {}
        self._latched: dict[str, list[Any]] = defaultdict(list)
        self._taps: list[Tap] = []

    def advertise(self, topic: str, message_type: type) -> None:
        """Declare ``topic`` to carry ``message_type``; later publishes are type-checked."""
        _check_name(topic)
        known = self._types.setdefault(topic, message_type)
        if known is not message_type:
            raise TopicError(f"topic {topic} carries {known.__name__}, not {message_type.__name__}")

    @property
    def topics(self) -> dict[str, type]:
        """Advertised topics and their message types."""
        return dict(self._types)

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        """Call ``callback(message)`` for every message on ``topic``.

        Latched messages already published on ``topic`` are delivered at once.
        """
        _check_name(topic)
        subscription = Subscription(topic, callback, self)
        self._subscriptions[topic].append(subscription)
        for message in self._latched.get(topic, ()):
            callback(message)
        return subscription

    def subscribe_all(self, callback: Callable[[str, Any], None]) -> Tap:
        """Call ``callback(topic, message)`` for every message on every topic (recorders,
        bridges). Latched messages are not replayed; read :meth:`latched` for those."""
        tap = Tap(callback, self)
        self._taps.append(tap)
        return tap

    def latched(self, topic: str) -> list[Any]:
        """The latched messages of ``topic`` (e.g. every arm's ``/tf_static``)."""
        return list(self._latched.get(topic, ()))

    def has_subscribers(self, topic: str) -> bool:
        return bool(self._taps) or bool(self._subscriptions.get(topic))

    def publish(self, topic: str, message: Any, *, latch: bool = False) -> None:
        """Deliver ``message`` to every subscriber of ``topic``.

        Args:
            latch: keep the message and replay it to future subscribers.
        """
        expected = self._types.get(topic)
        if expected is None:
            self.advertise(topic, type(message))
        elif not isinstance(message, expected):
            raise TopicError(
                f"topic {topic} carries {expected.__name__}, got {type(message).__name__}"
            )
        if latch:
            self._latched[topic].append(message)
        for subscription in tuple(self._subscriptions.get(topic, ())):
            subscription.callback(message)
        for tap in tuple(self._taps):
            tap.callback(topic, message)

    def forget_latched(self, topic: str, predicate: Callable[[Any], bool]) -> None:
        """Drop latched messages of ``topic`` for which ``predicate`` is true."""
        self._latched[topic] = [m for m in self._latched.get(topic, []) if not predicate(m)]

    def _remove(self, subscription: Subscription) -> None:
        subscribers = self._subscriptions.get(subscription.topic, [])
        if subscription in subscribers:
            subscribers.remove(subscription)


def _check_name(topic: str) -> None:
    if not isinstance(topic, str) or not TOPIC_PATTERN.fullmatch(topic):
        raise TopicError(
            f"topic name {topic!r} is malformed; use /segment[/segment...] with lowercase "
            "letters, digits and '_' (e.g. /bob/joint_states)"
        )
