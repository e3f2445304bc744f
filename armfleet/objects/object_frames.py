"""Scene objects' frames: ``world -> <object>`` on ``/tf`` (moving) or ``/tf_static`` (static).

As the arms' robot_state_publisher: a static object's transform is latched on
``/tf_static`` when it is added (again when it is teleported) and withdrawn
when it is removed; moving objects' transforms go out on ``/tf`` after every
step, one message for all of them, but only while someone listens.
"""

from __future__ import annotations

from collections.abc import Iterable

from armfleet import topics
from armfleet.frames.tf_tree import WORLD_FRAME
from armfleet.messages import TFMessage, TransformStamped
from armfleet.objects.world_object import WorldObject
from armfleet.runtime.bus import Bus


class ObjectFramePublisher:
    """Publishes the frames of one world's objects.

    Args:
        bus: the world's bus.
    """

    def __init__(self, bus: Bus) -> None:
        self._bus = bus
        self._static: dict[str, TFMessage] = {}
        bus.advertise(topics.TF, TFMessage)
        bus.advertise(topics.TF_STATIC, TFMessage)

    def latch(self, obj: WorldObject, stamp: float) -> None:
        """Latch a static object's transform on ``/tf_static`` (replacing an older one)."""
        self.withdraw(obj.name)
        message = TFMessage((TransformStamped(stamp, WORLD_FRAME, obj.name, obj.pose),))
        self._static[obj.name] = message
        self._bus.publish(topics.TF_STATIC, message, latch=True)

    def withdraw(self, name: str) -> None:
        """Forget the latched transform of object ``name``, if any."""
        message = self._static.pop(name, None)
        if message is not None:
            self._bus.forget_latched(topics.TF_STATIC, lambda latched: latched is message)

    def publish(self, stamp: float, moving: Iterable[WorldObject]) -> None:
        """Publish the transforms of the ``moving`` objects on ``/tf`` if anyone listens."""
        if not self._bus.has_subscribers(topics.TF):
            return
        transforms = tuple(TransformStamped(stamp, WORLD_FRAME, o.name, o.pose) for o in moving)
        if transforms:
            self._bus.publish(topics.TF, TFMessage(transforms))
