"""In-process publish/subscribe bus with ROS-style topic names.

Callbacks run synchronously in the publishing thread (the one stepping the
world), so the world stays single-threaded and deterministic. Latched topics
(like ROS transient-local ``/tf_static``) replay their messages to late
subscribers.

Subscribers are isolated from the publisher: a callback that raises is logged
once (topic, callback, traceback), counted in :attr:`Bus.failures` and dropped;
the publisher (a broadcaster inside a controller update, an arm sending a
command) never sees the exception, so a bug in a passive listener (logging,
plotting, a recorder) cannot stop a robot. The one exception is a subscriber
that owns its failures: the controllers' own command subscriptions pass
``on_error`` (their controller's :meth:`~armfleet.controllers.Controller.fail`),
because a command half-applied by a broken controller must put its arm in
``error`` rather than be skipped. armfleet's other internal subscribers are
passive and isolated like any listener: the robot_state_publisher (``/tf`` from
``/<arm>/joint_states``), bring-up's first-state watch, the recorder, the
viewer, and the live API's per-client queues.

Topics can go away (:meth:`Bus.unadvertise`, when an arm is removed); their
subscribers are told through ``on_gone``.

A subscriber that wants a stream at a display rate, not every step, passes
``period_s``: it then gets the messages of one instant of simulated time per
period (every arm's ``/tf`` of that step, not one arm's), and while none of a
topic's subscribers is due, :meth:`Bus.has_subscribers` says no, so the topics
computed only for listeners (``/tf``, a controller's state) are not computed at all.
"""

from __future__ import annotations

import functools
import logging
import math
import re
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from armfleet.checks.flags import flag
from armfleet.checks.real_numbers import real_number
from armfleet.errors import ArmfleetError, InvalidNumber

logger = logging.getLogger("armfleet")

Callback = Callable[[Any], None]
ErrorHandler = Callable[[Exception], None]
GoneHandler = Callable[[str, str], None]
TOPIC_PATTERN = re.compile(r"^(/[a-z][a-z0-9_]*)+$")


class BusError(ArmfleetError):
    """An argument the bus refuses where it is taken (a topic, a callback)."""


class TopicError(BusError):
    """A malformed topic name, or a message of the wrong type for a topic."""


class CallbackError(BusError):
    """Something that is not a function given where the bus calls one back.

    Attributes:
        role: what it was given as (``"callback"``, ``"on_error"``, ``"on_gone"``).
        got: the type name of what was given.
    """

    def __init__(self, call: str, role: str, got: object) -> None:
        self.role, self.got = role, type(got).__name__
        super().__init__(f"{call}: {role} must be a function (or callable), got {self.got}")


@dataclass(frozen=True)
class SubscriberFailure:
    """A subscriber the bus dropped because its callback raised.

    Attributes:
        topic: the topic it listened to (``*`` for a :meth:`Bus.subscribe_all` tap).
        callback: the callback's qualified name.
        error: the exception it raised.
    """

    topic: str
    callback: str
    error: Exception

    def __str__(self) -> str:
        return (
            f"subscriber {self.callback} of {self.topic} raised "
            f"{type(self.error).__name__}: {self.error}; it was dropped"
        )


@dataclass(eq=False)
class Subscription:
    """Handle returned by :meth:`Bus.subscribe`; call :meth:`cancel` to stop.

    Attributes:
        failure: why the bus dropped it (its callback raised), or None.
    """

    topic: str
    callback: Callback
    _bus: Bus | None = field(repr=False, default=None)
    on_error: ErrorHandler | None = field(repr=False, default=None)
    on_gone: GoneHandler | None = field(repr=False, default=None)
    failure: SubscriberFailure | None = None
    #: At most one instant of simulated time per period [s]; None: every message.
    period_s: float | None = None
    #: The instant being delivered (simulated time [s]), and when the next one is due.
    _instant: float = field(repr=False, default=-math.inf)
    _next_due: float = field(repr=False, default=-math.inf)

    @property
    def active(self) -> bool:
        """Whether messages still reach the callback (not cancelled, not dropped)."""
        return self._bus is not None

    def cancel(self) -> None:
        if self._bus is not None:
            self._bus._remove(self)
            self._bus = None

    def wants(self, now: float) -> bool:
        """Whether a message published at simulated time ``now`` is for it."""
        return self.period_s is None or now == self._instant or now >= self._next_due

    def take(self, now: float) -> bool:
        """:meth:`wants`, starting a new instant when one is due."""
        if self.period_s is None or now == self._instant:
            return True
        if now < self._next_due:
            return False
        self._instant = now
        # Due again a period on; the margin keeps a period that is a whole number of
        # steps from slipping a step on rounding.
        self._next_due = now + self.period_s * (1.0 - 1e-9)
        return True


@dataclass(eq=False)
class Tap:
    """Handle returned by :meth:`Bus.subscribe_all`; call :meth:`cancel` to stop.

    Attributes:
        failure: why the bus dropped it (its callback raised), or None.
    """

    callback: Callable[[str, Any], None]
    _bus: Bus | None = field(repr=False, default=None)
    failure: SubscriberFailure | None = None

    @property
    def active(self) -> bool:
        return self._bus is not None

    def cancel(self) -> None:
        if self._bus is not None and self in self._bus._taps:
            self._bus._taps.remove(self)
        self._bus = None


class Bus:
    """Topics of one world."""

    def __init__(self, clock: Callable[[], float] | None = None) -> None:
        """Args:
        clock: the simulated time [s], for subscribers that pass ``period_s``; a bus
            without one delivers them every message.
        """
        self._clock = clock
        self._subscriptions: dict[str, list[Subscription]] = defaultdict(list)
        self._types: dict[str, type] = {}
        self._latched: dict[str, list[Any]] = defaultdict(list)
        self._taps: list[Tap] = []
        self._failures: list[SubscriberFailure] = []

    def advertise(self, topic: str, message_type: type) -> None:
        """Declare ``topic`` to carry ``message_type``; later publishes are type-checked."""
        _check_name(topic)
        known = self._types.setdefault(topic, message_type)
        if known is not message_type:
            raise TopicError(f"topic {topic} carries {known.__name__}, not {message_type.__name__}")

    def unadvertise(self, namespace: str, reason: str) -> list[str]:
        """Withdraw every topic under ``namespace`` (``/ned``: ``/ned/joint_states`` ...).

        Their types and latched messages are forgotten, so they leave
        :attr:`topics`; each subscriber of a topic under ``namespace`` (advertised
        yet or not) is told through its ``on_gone(topic, reason)`` and stays
        subscribed: a topic advertised again under the same name (a new arm of the
        same name) reaches it again.

        Args:
            namespace: ``/segment[/segment...]``.
            reason: why, for the subscribers (``"arm ned was removed"``).

        Returns:
            The withdrawn topics.
        """
        _check_name(namespace)
        prefix = namespace + "/"
        gone = [t for t in self._types if t.startswith(prefix)]
        for topic in gone:
            del self._types[topic]
            self._latched.pop(topic, None)
        listened = [t for t, s in self._subscriptions.items() if s and t.startswith(prefix)]
        for topic in listened:
            for subscription in tuple(self._subscriptions.get(topic, ())):
                if subscription.on_gone is not None:
                    self._call(subscription, functools.partial(subscription.on_gone, topic), reason)
        return gone

    @property
    def topics(self) -> dict[str, type]:
        """Advertised topics and their message types."""
        return dict(self._types)

    @property
    def failures(self) -> tuple[SubscriberFailure, ...]:
        """The subscribers dropped so far because their callback raised, oldest first."""
        return tuple(self._failures)

    def subscribe(
        self,
        topic: str,
        callback: Callback,
        *,
        on_error: ErrorHandler | None = None,
        on_gone: GoneHandler | None = None,
        period_s: float | None = None,
    ) -> Subscription:
        """Call ``callback(message)`` for every message on ``topic``.

        Latched messages already published on ``topic`` are delivered at once.

        Args:
            on_error: called with the exception if ``callback`` raises, for a
                subscriber that must handle its own failures (a controller's command
                subscription). Without it a raising callback is logged, counted in
                :attr:`failures` and dropped; the publisher never sees the exception.
            on_gone: called with the topic and why when it is withdrawn (:meth:`unadvertise`).
            period_s: deliver the messages of one instant of simulated time per
                ``period_s`` [s] (a display rate) rather than every message; a topic
                whose subscribers are all between two instants is not computed.
        """
        _check_name(topic)
        if period_s is not None:
            valid = "a period > 0 s (None: every message)"
            period_s = real_number(period_s, "period_s", valid, low=0.0)
            if period_s == 0.0:
                raise InvalidNumber("period_s", period_s, valid)
        _check_callable("subscribe", "callback", callback)
        _check_callable("subscribe", "on_error", on_error, optional=True)
        _check_callable("subscribe", "on_gone", on_gone, optional=True)
        subscription = Subscription(topic, callback, self, on_error, on_gone, period_s=period_s)
        self._subscriptions[topic].append(subscription)
        for message in self._latched.get(topic, ()):
            if not self._call(subscription, callback, message):
                break
        return subscription

    def subscribe_all(self, callback: Callable[[str, Any], None]) -> Tap:
        """Call ``callback(topic, message)`` for every message on every topic (recorders,
        bridges). Latched messages are not replayed; read :meth:`latched` for those."""
        _check_callable("subscribe_all", "callback", callback)
        tap = Tap(callback, self)
        self._taps.append(tap)
        return tap

    def latched(self, topic: str) -> list[Any]:
        """The latched messages of ``topic`` (e.g. every arm's ``/tf_static``)."""
        _check_name(topic)
        return list(self._latched.get(topic, ()))

    def has_subscribers(self, topic: str) -> bool:
        """Whether a message on ``topic`` published now would reach anyone: a tap, or a
        subscriber that takes every message or is due at this instant (``period_s``)."""
        if not (isinstance(topic, str) and topic in self._types):  # advertised: checked
            _check_name(topic)  # the controllers ask every step: not their own topics again
        subscribers = self._subscriptions.get(topic)
        if self._taps or not subscribers:
            return bool(self._taps)
        if self._clock is None or any(s.period_s is None for s in subscribers):
            return True  # asked every step by the publishers: no clock read for plain ones
        now = self._clock()
        return any(s.wants(now) for s in subscribers)

    def publish(self, topic: str, message: Any, *, latch: bool = False) -> None:
        """Deliver ``message`` to every subscriber of ``topic``.

        Args:
            latch: keep the message and replay it to future subscribers.
        """
        if latch is not False:
            latch = flag(latch, "latch")
        # A known topic is a checked one; anything else (a list: no unhashable-key
        # TypeError) goes through advertise, which checks the name.
        expected = self._types.get(topic) if isinstance(topic, str) else None
        if expected is None:
            self.advertise(topic, type(message))
        elif not isinstance(message, expected):
            raise TopicError(
                f"topic {topic} carries {expected.__name__}, got {type(message).__name__}"
            )
        if latch:
            self._latched[topic].append(message)
        now: float | None = None
        for subscription in tuple(self._subscriptions.get(topic, ())):
            if subscription.period_s is not None and self._clock is not None:
                if now is None:
                    now = self._clock()
                if not subscription.take(now):
                    continue
            try:
                subscription.callback(message)
            except Exception as exc:
                self._failed(subscription, exc)
        for tap in tuple(self._taps):
            try:
                tap.callback(topic, message)
            except Exception as exc:
                self._failed(tap, exc)

    def forget_latched(self, topic: str, predicate: Callable[[Any], bool]) -> None:
        """Drop latched messages of ``topic`` for which ``predicate`` is true."""
        self._latched[topic] = [m for m in self._latched.get(topic, []) if not predicate(m)]

    def _call(self, subscription: Subscription, function: Callable[[Any], None], arg: Any) -> bool:
        """``function(arg)`` on behalf of ``subscription``; False if it raised."""
        try:
            function(arg)
        except Exception as exc:
            self._failed(subscription, exc)
            return False
        return True

    def _failed(self, subscriber: Subscription | Tap, exc: Exception) -> None:
        """A subscriber's callback raised ``exc``: its owner handles it, or it is dropped."""
        if isinstance(subscriber, Subscription) and subscriber.on_error is not None:
            subscriber.on_error(exc)
            return
        topic = subscriber.topic if isinstance(subscriber, Subscription) else "*"
        failure = SubscriberFailure(topic, _callback_name(subscriber.callback), exc)
        subscriber.failure = failure
        subscriber.cancel()
        self._failures.append(failure)
        logger.error("%s", failure, exc_info=exc)

    def _remove(self, subscription: Subscription) -> None:
        subscribers = self._subscriptions.get(subscription.topic, [])
        if subscription in subscribers:
            subscribers.remove(subscription)


def _callback_name(callback: Callable[..., Any]) -> str:
    name = getattr(callback, "__qualname__", None) or getattr(callback, "__name__", None)
    if name is None:  # functools.partial, callable objects
        inner = getattr(callback, "func", None)
        return _callback_name(inner) if inner is not None else repr(callback)
    module = getattr(callback, "__module__", None)
    return f"{module}.{name}" if module else str(name)


def _check_callable(call: str, role: str, value: object, *, optional: bool = False) -> None:
    """The one rule for the functions the bus calls back: refused when taken, not per step."""
    if not (callable(value) or (optional and value is None)):
        raise CallbackError(call, role, value)


def _check_name(topic: str) -> None:
    if not isinstance(topic, str) or not TOPIC_PATTERN.fullmatch(topic):
        raise TopicError(
            f"topic name {topic!r} is malformed; use /segment[/segment...] with lowercase "
            "letters, digits and '_' (e.g. /bob/joint_states)"
        )
