"""The handle :meth:`Client.subscribe` returns."""

from __future__ import annotations

from collections.abc import Callable

from armfleet.remote.stream_receiver import LocalSubscription


class RemoteSubscription:
    """A topic a client receives; its callback runs in the client's stream thread.

    Attributes:
        topic: the topic.
        type_name: its message type.
    """

    def __init__(
        self, local: LocalSubscription, type_name: str, cancel: Callable[[int], None]
    ) -> None:
        self._local = local
        self.topic = local.topic
        self.type_name = type_name
        self._cancel = cancel

    @property
    def received(self) -> int:
        """Messages handed to the callback so far."""
        return self._local.received

    @property
    def dropped(self) -> int:
        """Messages dropped (oldest first) because the callback or the link fell behind."""
        return self._local.dropped_by_world + self._local.dropped_here

    @property
    def active(self) -> bool:
        return not self._local.ended.is_set()

    @property
    def error(self) -> BaseException | None:
        """Why the subscription ended on its own: the world closed or went silent
        (:class:`ConnectionLost`), or its topic went away (:class:`TopicGone`, e.g. its
        arm was removed)."""
        return self._local.error

    def wait_ended(self, timeout: float | None = None) -> bool:
        """Block until the subscription ends (cancelled, or the world went away)."""
        return self._local.ended.wait(timeout)

    def cancel(self) -> None:
        """Stop receiving (idempotent)."""
        if self.active:
            self._cancel(self._local.key)

    def __repr__(self) -> str:
        state = "active" if self.active else "ended"
        return f"RemoteSubscription({self.topic!r}, {self.type_name}, {state})"
