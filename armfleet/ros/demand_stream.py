"""A streamed topic computed only while a ROS 2 node subscribes to it.

``/tf`` and the joint states come from the world's bus at the publication rate; a bus
subscription makes the world compute them (``/tf``: forward kinematics of every arm).
With nobody subscribed on the ROS side, that work would be thrown away: the stream
follows its publisher's subscription count, checked at each publication instant, and
holds a bus subscription only while the count is above 0.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rclpy.publisher import Publisher

    from armfleet.runtime.bus import Bus, Subscription


class DemandStream:
    """Bus topic ``topic`` to ROS ``publisher``, through ``convert``, while subscribed."""

    def __init__(
        self,
        bus: Bus,
        topic: str,
        publisher: Publisher[Any],
        convert: Callable[[Any], bytes],
        period_s: float,
    ) -> None:
        self._bus = bus
        self._topic = topic
        self._publisher = publisher
        self._convert = convert
        self._period_s = period_s
        self._subscription: Subscription | None = None

    @property
    def flowing(self) -> bool:
        return self._subscription is not None

    def refresh(self) -> None:
        """Follow the publisher's subscription count (stepping thread)."""
        wanted = self._publisher.get_subscription_count() > 0
        if wanted and self._subscription is None:
            self._subscription = self._bus.subscribe(
                self._topic, self._deliver, period_s=self._period_s
            )
        elif not wanted and self._subscription is not None:
            self.close()

    def close(self) -> None:
        if self._subscription is not None:
            self._subscription.cancel()
            self._subscription = None

    def _deliver(self, message: Any) -> None:
        self._publisher.publish(self._convert(message))
