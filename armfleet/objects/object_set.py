"""The scene objects of one world: made, followed after each step, framed and removed.

Names are checked here against each other; :class:`armfleet.World` checks them
against its arms before calling :meth:`ObjectSet.add`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from armfleet.errors import UnknownObject
from armfleet.objects.arm_path_clearance import ArmMotion
from armfleet.objects.object_clearance import check_object_clearance, place_clear_object
from armfleet.objects.object_frames import ObjectFramePublisher
from armfleet.objects.object_spec import ObjectSpec
from armfleet.objects.world_object import WorldObject
from armfleet.physics.contact_monitor import ContactMonitor
from armfleet.runtime.bus import Bus
from armfleet.runtime.lifetime import Lifetime


class ObjectSet:
    """Objects by name, in the order they were added.

    Args:
        client: PyBullet client id of the world.
        bus: the world's bus (``/tf``, ``/tf_static``).
        contacts: the world's contact monitor, told of every body.
        lifetime: the world's; every object gets a child of it, ended when the
            object is removed (its handles then raise :class:`UnknownObject`).
        on_remove: the world's removal of an object by name, which
            :meth:`WorldObject.remove` calls, so that removing through the handle
            takes out everything the world keeps of it.
    """

    def __init__(
        self,
        client: int,
        bus: Bus,
        contacts: ContactMonitor,
        lifetime: Lifetime | None = None,
        on_remove: Callable[[str], None] | None = None,
    ) -> None:
        self._client = client
        self._on_remove = on_remove
        self._lifetime = lifetime
        self._contacts = contacts
        self._frames = ObjectFramePublisher(bus)
        self._objects: dict[str, WorldObject] = {}
        self._moving: tuple[WorldObject, ...] = ()
        self._stamp = 0.0

    @property
    def objects(self) -> dict[str, WorldObject]:
        """Objects by name (a copy)."""
        return dict(self._objects)

    def __contains__(self, name: object) -> bool:
        return name in self._objects

    def __len__(self) -> int:
        return len(self._objects)

    def get(self, name: str) -> WorldObject:
        """The object ``name``; :class:`UnknownObject` lists the others."""
        if not isinstance(name, str) or name not in self._objects:  # a list is no name either
            raise UnknownObject(name, list(self._objects))
        return self._objects[name]

    def add(self, spec: ObjectSpec, stamp: float, motions: Iterable[ArmMotion] = ()) -> WorldObject:
        """Make ``spec``'s body and frame at simulated time ``stamp`` [s] (name already checked).

        Args:
            motions: the moving arms' remaining motions, which it must keep clear of.

        Raises:
            ObjectCollision: it would touch an arm or overlap the floor or an object
                (:mod:`armfleet.objects.object_clearance`); nothing was added.
            ObjectInArmPath: it stands in a moving arm's path
                (:mod:`armfleet.objects.arm_path_clearance`); nothing was added.
        """
        name = spec.name
        lifetime = Lifetime(lambda: UnknownObject(name, list(self._objects)), self._lifetime)
        obj = place_clear_object(
            self._client,
            spec,
            self._contacts.neighbours(),
            self._teleported,
            lifetime,
            self._on_remove,
            motions,
        )
        self._objects[obj.name] = obj
        self._contacts.add_object(obj.name, obj.body_id, static=obj.is_static)
        if obj.is_static:
            self._frames.latch(obj, stamp)
        self._update_moving()
        return obj

    def remove(self, name: str) -> WorldObject:
        """Take object ``name`` out: frame, contacts, body. Returns it (removed)."""
        obj = self.get(name)
        self._frames.withdraw(name)
        self._contacts.remove_object(obj.body_id)
        obj.discard_body()
        del self._objects[name]
        self._update_moving()
        return obj

    def after_step(self, stamp: float) -> None:
        """The world stepped to ``stamp`` [s]: poses are stale; moving frames go on ``/tf``."""
        self._stamp = stamp
        for obj in self._moving:
            obj.stale()
        if self._moving:
            self._frames.publish(stamp, self._moving)

    def clear(self) -> None:
        """Remove every object."""
        for name in list(self._objects):
            self.remove(name)

    def _teleported(self, obj: WorldObject) -> None:
        others = (n for n in self._contacts.neighbours() if n.body_id != obj.body_id)
        check_object_clearance(
            self._client, obj.name, obj.body_id, obj.is_static, others, "it was not moved"
        )
        if obj.is_static:
            self._frames.latch(obj, self._stamp)

    def _update_moving(self) -> None:
        self._moving = tuple(o for o in self._objects.values() if not o.is_static)
