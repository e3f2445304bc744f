"""The bounded queue between the stepping thread and a subscriber: never blocks the world."""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any


class SubscriptionQueue:
    """Messages of one subscription waiting to be sent, oldest dropped when full.

    :meth:`push` runs in the stepping thread (as a bus callback) and costs a few
    microseconds whatever the client does; the server thread :meth:`pop` s.

    Args:
        size: messages held at most.
        rate_hz: keep at most this many messages per second of wall time; all if None.
        on_push: called after a message is queued (wakes the sender).
    """

    def __init__(
        self,
        size: int,
        rate_hz: float | None = None,
        on_push: Callable[[], None] | None = None,
    ) -> None:
        if size < 1:
            raise ValueError(f"queue size {size} must be >= 1")
        self._items: deque[Any] = deque(maxlen=size)
        self._period = 1.0 / rate_hz if rate_hz else 0.0
        self._next_due = -math.inf
        self._on_push = on_push
        self._dropped = 0
        self._accepted = 0
        self._closed = False
        self._gone: str | None = None

    @property
    def dropped(self) -> int:
        """Messages pushed out unsent because the subscriber fell behind."""
        return self._dropped

    @property
    def accepted(self) -> int:
        """Messages queued (after rate limiting)."""
        return self._accepted

    def push(self, message: Any) -> None:
        if self._closed:
            return
        if self._period:
            now = time.monotonic()
            if now < self._next_due:
                return
            # Steady rate without drift, and no burst after a quiet spell.
            self._next_due = max(self._next_due + self._period, now + 0.5 * self._period)
        items = self._items
        if len(items) == items.maxlen:
            self._dropped += 1
        items.append(message)
        self._accepted += 1
        if self._on_push is not None:
            self._on_push()

    def topic_gone(self, topic: str, reason: str) -> None:
        """The topic was withdrawn (a bus ``on_gone`` callback, in the stepping thread)."""
        self._gone = f"topic {topic} is gone: {reason}"

    @property
    def gone(self) -> str | None:
        """Why the topic went away, or None while it exists."""
        return self._gone

    def pop(self) -> Any | None:
        """The oldest queued message, or None."""
        try:
            return self._items.popleft()
        except IndexError:
            return None

    def close(self) -> None:
        """Ignore further messages (the subscriber is gone) and forget the queued ones."""
        self._closed = True
        self._items.clear()

    def __len__(self) -> int:
        return len(self._items)
