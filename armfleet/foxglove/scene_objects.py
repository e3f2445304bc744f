"""The world's objects drawn in Foxglove's 3D panel: ``/scene_objects``.

An object has no topic of its own on the bus: its frame is on ``/tf`` (moving) or
``/tf_static`` (static) as ``world -> <object>``, its shape is in the world. This
channel carries Foxglove's own ``foxglove.SceneUpdate`` (the SDK's typed channel,
protobuf), one entity per object, attached to the object's frame (``frame_locked``): the
3D panel draws each box, cylinder, sphere or mesh where TF puts it, in its colour, and it
moves with ``/tf``. A mesh goes out as its file's bytes (STL or OBJ), scaled as the world
scaled it.

An update is sent to a client when it subscribes (everything, after deleting whatever it
showed before), and when objects come or go (checked on the arms' status ticks, 10 Hz of
simulated time): nothing is sent while nobody subscribes.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import foxglove
from foxglove.channels import SceneUpdateChannel
from foxglove.messages import (
    Color,
    CubePrimitive,
    CylinderPrimitive,
    ModelPrimitive,
    SceneEntity,
    SceneEntityDeletion,
    SceneEntityDeletionType,
    SceneUpdate,
    SpherePrimitive,
    Vector3,
)

from armfleet import topics
from armfleet.objects.object_spec import Shape
from armfleet.recording.encode import stamp_ns

if TYPE_CHECKING:
    from armfleet.objects import WorldObject
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: The channel's topic.
#: Media types of the mesh files objects are made from, by suffix.
MESH_MEDIA_TYPES = {".stl": "model/stl", ".obj": "model/obj"}


class SceneObjects:
    """The ``/scene_objects`` channel of one server (stepping thread only).

    Args:
        world: the world whose objects are drawn.
        context: the server's SDK context.
    """

    def __init__(self, world: World, context: foxglove.Context) -> None:
        self._world = world
        self._channel = SceneUpdateChannel(topics.SCENE_OBJECTS, context=context)
        #: Object name -> the object drawn (a new object of the same name is redrawn).
        self._drawn: dict[str, WorldObject] = {}
        #: Updates handed to the server so far.
        self.sent = 0

    @property
    def channel_id(self) -> int:
        return self._channel.id()

    def refresh(self) -> None:
        """Send the objects added and removed since the last call (if anyone listens)."""
        objects = self._world.objects
        gone = [name for name, drawn in self._drawn.items() if objects.get(name) is not drawn]
        new = [obj for name, obj in objects.items() if self._drawn.get(name) is not obj]
        if not (gone or new):
            return
        for name in gone:
            del self._drawn[name]
        self._drawn.update((obj.name, obj) for obj in new)
        if self._channel.has_sinks():
            deletions = [_deletion(name) for name in gone]
            self._log(SceneUpdate(deletions=deletions, entities=self._entities(new)))

    def resend(self) -> None:
        """Send every object again, after deleting what the clients showed (a client
        that just subscribed)."""
        self.refresh()
        if self._channel.has_sinks():
            everything = SceneEntityDeletion(type=SceneEntityDeletionType.All)
            entities = self._entities(list(self._drawn.values()))
            self._log(SceneUpdate(deletions=[everything], entities=entities))

    def close(self) -> None:
        self._channel.close()

    def _log(self, update: SceneUpdate) -> None:
        self._channel.log(update, log_time=stamp_ns(self._world.time))
        self.sent += 1

    def _entities(self, objects: list[WorldObject]) -> list[SceneEntity]:
        entities = []
        for obj in objects:
            try:
                entities.append(entity(obj))
            except OSError as exc:  # a mesh file gone since the object was added
                logger.warning("foxglove: cannot draw object %s: %s", obj.name, exc)
        return entities


def entity(obj: WorldObject) -> SceneEntity:
    """The scene entity of ``obj``: its shape in its own frame, in its colour.

    Raises:
        OSError: a mesh object's file cannot be read.
    """
    r, g, b, a = obj.color
    color = Color(r=r, g=g, b=b, a=a)
    size = obj.size
    cubes, cylinders, spheres, models = [], [], [], []
    if obj.shape is Shape.BOX:
        cubes.append(CubePrimitive(size=Vector3(x=size[0], y=size[1], z=size[2]), color=color))
    elif obj.shape is Shape.CYLINDER:  # (radius, length); scales 1: neither end narrows
        extent = Vector3(x=2 * size[0], y=2 * size[0], z=size[1])
        cylinders.append(
            CylinderPrimitive(size=extent, bottom_scale=1.0, top_scale=1.0, color=color)
        )
    elif obj.shape is Shape.SPHERE:  # (radius,)
        diameter = 2 * size[0]
        spheres.append(
            SpherePrimitive(size=Vector3(x=diameter, y=diameter, z=diameter), color=color)
        )
    else:
        models.append(_model(obj, color))
    return SceneEntity(
        frame_id=obj.name,
        id=obj.name,
        frame_locked=True,
        cubes=cubes,
        cylinders=cylinders,
        spheres=spheres,
        models=models,
    )


def _model(obj: WorldObject, color: Color) -> ModelPrimitive:
    path = obj.mesh
    assert path is not None  # a mesh object has its file
    scale = obj.spec.scale
    return ModelPrimitive(
        scale=Vector3(x=scale, y=scale, z=scale),
        color=color,
        override_color=True,
        media_type=MESH_MEDIA_TYPES.get(path.suffix.lower(), "model/stl"),
        data=path.read_bytes(),
    )


def _deletion(name: str) -> SceneEntityDeletion:
    return SceneEntityDeletion(type=SceneEntityDeletionType.MatchingId, id=name)
