"""An arm's visual geometry as a ``foxglove.SceneUpdate``, meshes inside: ``/<arm>/robot_meshes``.

A recording's ``/<arm>/robot_description`` names its meshes by ``file://`` paths of the
machine that recorded it: Foxglove and Lichtblick refuse those (and another machine has
no such files), so a URDF layer draws nothing there and the 3D panel shows only the TF
axes. This message makes a recording self-contained: one entity per link that has visual
geometry, attached to the link's TF frame (``frame_locked``), holding each visual as
Foxglove's own primitives: a ``ModelPrimitive`` whose ``data`` is the mesh file's bytes
with its ``media_type`` (COLLADA, STL, OBJ or glTF, the formats Foxglove's model loader
reads, the very loader its URDF layer uses), or a cube, cylinder or sphere, at the
visual's origin, scale and colour.

JSON like every recorded message: Foxglove's JSON reader turns a string field whose
schema says ``"contentEncoding": "base64"`` into bytes, which is how ``data`` travels.
Every field of the schema has one JSON type, and every message holds every field (the
3D panel reads them all). A Panda's meshes are 10.6 MB of COLLADA: about 5 MB of the
file, once per arm. The recorder logs the message at the arm's arrival and writes it as
the file is completed (a run cut short has none).
"""

from __future__ import annotations

import base64
import math
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from armfleet.recording.encode import dumps
from armfleet.recording.schemas import MessageSchema, Schema

#: The schema name Foxglove's 3D panel draws.
SCENE_UPDATE = "foxglove.SceneUpdate"
#: Media types of the mesh files Foxglove's model loader reads, by suffix.
MESH_MEDIA_TYPES = {
    ".dae": "model/vnd.collada+xml",
    ".stl": "model/stl",
    ".obj": "model/obj",
    ".glb": "model/gltf-binary",
    ".gltf": "model/gltf+json",
}


def robot_meshes_topic(arm: str) -> str:
    """The arm's visual geometry with its meshes (``foxglove.SceneUpdate``, recordings)."""
    return f"/{arm}/robot_meshes"


# -- the schema: Foxglove's SceneUpdate, the fields armfleet writes ------------------------
def _object(**properties: Schema) -> Schema:
    return {"type": "object", "properties": properties, "required": sorted(properties)}


def _numbers(*names: str) -> Schema:
    return _object(**{name: {"type": "number"} for name in names})


_TIME = _object(sec={"type": "integer"}, nsec={"type": "integer"})
_VECTOR = _numbers("x", "y", "z")
_POSE = _object(position=_VECTOR, orientation=_numbers("x", "y", "z", "w"))
_COLOR = _numbers("r", "g", "b", "a")
_CUBE = _object(pose=_POSE, size=_VECTOR, color=_COLOR)
_CYLINDER = _object(
    pose=_POSE,
    size=_VECTOR,
    bottom_scale={"type": "number"},
    top_scale={"type": "number"},
    color=_COLOR,
)
_MODEL = _object(
    pose=_POSE,
    scale=_VECTOR,
    color=_COLOR,
    override_color={"type": "boolean"},
    url={"type": "string"},
    media_type={"type": "string"},
    data={"type": "string", "contentEncoding": "base64"},
)
_UNUSED: Schema = {"type": "array", "items": {"type": "object", "properties": {}}}
_ENTITY = _object(
    timestamp=_TIME,
    frame_id={"type": "string"},
    id={"type": "string"},
    lifetime=_TIME,
    frame_locked={"type": "boolean"},
    metadata={"type": "array", "items": _object(key={"type": "string"}, value={"type": "string"})},
    arrows=_UNUSED,
    cubes={"type": "array", "items": _CUBE},
    spheres={"type": "array", "items": _CUBE},
    cylinders={"type": "array", "items": _CYLINDER},
    lines=_UNUSED,
    triangles=_UNUSED,
    texts=_UNUSED,
    models={"type": "array", "items": _MODEL},
)
ROBOT_MESHES = MessageSchema(
    SCENE_UPDATE,
    {
        "title": SCENE_UPDATE,
        "description": "An update to the entities of a 3D scene (Foxglove's schema)",
        **_object(deletions=_UNUSED, entities={"type": "array", "items": _ENTITY}),
    },
)


# -- the URDF's visuals -------------------------------------------------------------------
@dataclass(frozen=True)
class Visual:
    """One ``<visual>`` of a link, resolved: its origin, geometry and colour."""

    link: str
    #: Position [m] and quaternion (x, y, z, w) of the geometry in the link's frame.
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    #: ``mesh``, ``box``, ``cylinder`` or ``sphere``.
    kind: str
    #: The mesh file (absolute), for a mesh.
    mesh: Path | None
    #: Mesh scale, box size [m], (radius, length) [m] or (radius,) [m].
    dimensions: tuple[float, ...]
    #: The URDF's colour (r, g, b, a), if it gives one.
    rgba: tuple[float, float, float, float] | None


def urdf_visuals(urdf: str) -> list[Visual]:
    """Every visual of ``urdf`` (an expanded URDF with absolute mesh paths), in order.

    Raises:
        ValueError: the URDF is not XML, or a visual's numbers are malformed.
    """
    robot = ElementTree.fromstring(urdf)
    colors = {
        material.get("name", ""): _rgba(material)
        for material in robot.findall("material")
        if material.find("color") is not None
    }
    visuals = []
    for link in robot.findall("link"):
        for visual in link.findall("visual"):
            geometry = visual.find("geometry")
            shape = None if geometry is None else next(iter(geometry), None)
            if shape is None:
                continue
            origin = visual.find("origin")
            xyz = _floats(origin, "xyz", 3, 0.0)
            rpy = _floats(origin, "rpy", 3, 0.0)
            material = visual.find("material")
            rgba = None
            if material is not None:
                rgba = _rgba(material) or colors.get(material.get("name", ""))
            kind, mesh, dimensions = _geometry(shape)
            if kind is None:
                continue
            visuals.append(
                Visual(
                    link.get("name", ""),
                    (xyz[0], xyz[1], xyz[2]),
                    _quaternion(rpy[0], rpy[1], rpy[2]),
                    kind,
                    mesh,
                    dimensions,
                    rgba,
                )
            )
    return visuals


def _geometry(shape: ElementTree.Element) -> tuple[str | None, Path | None, tuple[float, ...]]:
    if shape.tag == "mesh":
        filename = shape.get("filename", "")
        filename = filename.removeprefix("file://")
        return "mesh", Path(filename), _floats(shape, "scale", 3, 1.0)
    if shape.tag == "box":
        return "box", None, _floats(shape, "size", 3, 0.0)
    if shape.tag == "cylinder":
        return "cylinder", None, (float(shape.get("radius", 0)), float(shape.get("length", 0)))
    if shape.tag == "sphere":
        return "sphere", None, (float(shape.get("radius", 0)),)
    return None, None, ()


def _floats(
    element: ElementTree.Element | None, name: str, count: int, default: float
) -> tuple[float, ...]:
    text = None if element is None else element.get(name)
    if text is None:
        return (default,) * count
    values = tuple(float(v) for v in text.split())
    if len(values) == 1 and count > 1:  # a single mesh scale applies to every axis
        values = values * count
    if len(values) != count:
        raise ValueError(
            f"<{getattr(element, 'tag', '')} {name}={text!r}>: expected {count} numbers"
        )
    return values


def _rgba(material: ElementTree.Element) -> tuple[float, float, float, float] | None:
    color = material.find("color")
    if color is None or color.get("rgba") is None:
        return None
    r, g, b, a = _floats(color, "rgba", 4, 1.0)
    return (r, g, b, a)


def _quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """URDF ``rpy`` (fixed axes X, then Y, then Z) as a quaternion (x, y, z, w)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


# -- the message --------------------------------------------------------------------------
def robot_meshes_message(urdf: str, time_ns: int) -> bytes:
    """The ``foxglove.SceneUpdate`` (JSON) drawing ``urdf``'s visuals, stamped ``time_ns``.

    Raises:
        OSError: a mesh file cannot be read.
        ValueError: the URDF is malformed.
    """
    entities: dict[str, dict[str, Any]] = {}
    meshes: dict[Path, str] = {}  # a file used twice is read and encoded once
    sec, nsec = divmod(time_ns, 1_000_000_000)
    for visual in urdf_visuals(urdf):
        entity = entities.setdefault(visual.link, _entity(visual.link, sec, nsec))
        pose = {
            "position": dict(zip("xyz", visual.position, strict=True)),
            "orientation": dict(zip("xyzw", visual.orientation, strict=True)),
        }
        color = dict(zip("rgba", visual.rgba or (1.0, 1.0, 1.0, 1.0), strict=True))
        size = visual.dimensions
        if visual.kind == "mesh":
            assert visual.mesh is not None
            if visual.mesh not in meshes:
                meshes[visual.mesh] = base64.b64encode(visual.mesh.read_bytes()).decode()
            entity["models"].append(
                {
                    "pose": pose,
                    "scale": dict(zip("xyz", size, strict=True)),
                    "color": color,
                    "override_color": visual.rgba is not None,
                    "url": "",
                    "media_type": MESH_MEDIA_TYPES.get(visual.mesh.suffix.lower(), "model/stl"),
                    "data": meshes[visual.mesh],
                }
            )
        elif visual.kind == "box":
            extent = dict(zip("xyz", size, strict=True))
            entity["cubes"].append({"pose": pose, "size": extent, "color": color})
        elif visual.kind == "cylinder":  # along z, as in URDF
            extent = {"x": 2 * size[0], "y": 2 * size[0], "z": size[1]}
            entity["cylinders"].append(
                {
                    "pose": pose,
                    "size": extent,
                    "bottom_scale": 1.0,
                    "top_scale": 1.0,
                    "color": color,
                }
            )
        else:
            diameter = 2 * size[0]
            extent = {"x": diameter, "y": diameter, "z": diameter}
            entity["spheres"].append({"pose": pose, "size": extent, "color": color})
    return dumps({"deletions": [], "entities": list(entities.values())})


def _entity(link: str, sec: int, nsec: int) -> dict[str, Any]:
    return {
        "timestamp": {"sec": sec, "nsec": nsec},
        "frame_id": link,
        "id": link,
        "lifetime": {"sec": 0, "nsec": 0},  # for ever
        "frame_locked": True,
        "metadata": [],
        "arrows": [],
        "cubes": [],
        "spheres": [],
        "cylinders": [],
        "lines": [],
        "triangles": [],
        "texts": [],
        "models": [],
    }
