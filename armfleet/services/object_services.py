"""Services for scene objects: ``objects``, ``add_object`` and ``remove_object``.

Boxes, cylinders and spheres only: a mesh object names a file on the world's
machine, which a client should not choose (add meshes from Python or a launch
spec). Everything else is checked by the world, as :meth:`World.add_object`
checks it, with its messages.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pinocchio as pin

from armfleet.errors import ObjectError
from armfleet.objects.object_spec import Shape
from armfleet.objects.world_object import WorldObject
from armfleet.services.arguments import Arguments
from armfleet.services.codec import to_wire
from armfleet.world import World

Work = Callable[[], Any]

#: Shapes a client may add.
REMOTE_SHAPES = tuple(s.value for s in Shape if s is not Shape.MESH)


class ObjectServices:
    """The object services of one world."""

    def __init__(self, world: World) -> None:
        self._world = world

    def prepare_objects(self, args: Arguments) -> Work:
        world = self._world
        return lambda: [describe_object(obj) for obj in world.objects.values()]

    def prepare_add_object(self, args: Arguments) -> Work:
        name, shape = args.text("name"), args.text("shape")
        if shape not in REMOTE_SHAPES:
            hint = (
                " (a mesh names a file on the world's machine: add it from Python or a launch spec)"
                if shape == Shape.MESH.value
                else ""
            )
            raise ObjectError(
                name, "shape", f"{shape!r} cannot be added here{hint}; shapes: "
                f"{', '.join(REMOTE_SHAPES)}"
            )  # fmt: skip
        options: dict[str, Any] = {}
        if isinstance(args.raw("size"), int | float) and not isinstance(args.raw("size"), bool):
            options["size"] = args.number("size", finite=False)
        elif args.has("size"):
            options["size"] = args.vector("size")
        # Non-finite numbers pass: the world names the field and its valid range.
        for key in ("mass", "friction"):
            if args.has(key):
                options[key] = args.number(key, finite=False)
        for key in ("color", "at", "rpy_deg"):
            if args.has(key):
                options[key] = args.vector(key)
        world = self._world

        def add_object() -> dict[str, Any]:
            return describe_object(world.add_object(name, shape, **options))

        return add_object

    def prepare_remove_object(self, args: Arguments) -> Work:
        name, world = args.text("name"), self._world

        def remove_object() -> dict[str, Any]:
            world.remove_object(name)
            return {"time_s": world.time, "objects": list(world.objects)}

        return remove_object


def describe_object(obj: WorldObject) -> dict[str, Any]:
    """An object as the ``objects`` and ``add_object`` services report it."""
    pose = obj.pose
    rpy = pin.rpy.matrixToRpy(pose[:3, :3])
    return {
        "name": obj.name,
        "shape": obj.shape.value,
        "size": list(obj.size),
        "mass": obj.mass,
        "static": obj.is_static,
        "position": to_wire(pose[:3, 3]),
        "rpy_deg": [math.degrees(float(a)) + 0.0 for a in rpy],  # + 0.0: no -0.0
    }
