"""The ``objects:`` list of a launch spec: boxes, cylinders, spheres and meshes.

Format (units in the key names; all keys but ``name``, ``shape`` and the size optional)::

    objects:
      - name: table
        shape: box                 # box, cylinder, sphere or mesh
        size_m: [0.8, 0.6, 0.4]    # box (x, y, z); cylinder [radius, length]; sphere radius
        mass_kg: 0                 # 0: static, fixed in the world
        at_m: [0.6, 0, 0.2]        # the object's centre (a mesh: its file's origin) [m]
        yaw_deg: 0                 # or yaw_rad, rpy_deg: [r, p, y], rpy_rad
        friction: 0.8              # lateral friction coefficient
        color_rgba: [0.6, 0.45, 0.3, 1]
      - name: cup
        shape: mesh
        mesh: meshes/cup.stl       # .obj or .stl, relative to the spec file
        scale: 0.001               # mm -> m

Every value goes through :func:`armfleet.objects.object_spec`, the check of
``World.add_object``; a problem is reported at the line of its key.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

from armfleet.checks.located_yaml import LocatedDict
from armfleet.errors import ObjectError
from armfleet.objects.object_spec import (
    DEFAULT_COLOR,
    DEFAULT_FRICTION,
    DEFAULT_MASS_KG,
    DEFAULT_ROLLING_FRICTION_M,
    DEFAULT_SPINNING_FRICTION_M,
    ObjectSpec,
    object_spec,
)
from armfleet.spec.spec_reader import SpecReader

ORIENTATION_KEYS = ("yaw_deg", "yaw_rad", "rpy_deg", "rpy_rad")
OBJECT_KEYS = (
    "name",
    "shape",
    "size_m",
    "mass_kg",
    "at_m",
    "friction",
    "spinning_friction_m",
    "rolling_friction_m",
    "color_rgba",
    "mesh",
    "scale",
    *ORIENTATION_KEYS,
)
#: ``object_spec`` argument -> spec key, to point at the right line.
_KEY_OF = {
    "size": "size_m",
    "mass": "mass_kg",
    "at": "at_m",
    "color": "color_rgba",
    "spinning_friction": "spinning_friction_m",
    "rolling_friction": "rolling_friction_m",
}

Orientation = Callable[[SpecReader, LocatedDict, str], tuple[float, float, float]]


def read_objects(
    reader: SpecReader,
    top: LocatedDict,
    base_dir: Path | None,
    arm_names: Collection[str],
    orientation: Orientation,
    on_object: Callable[[ObjectSpec, LocatedDict, str], None] | None = None,
) -> tuple[ObjectSpec, ...]:
    """Check the spec's ``objects:`` list; names must differ from each other and the arms'.

    Args:
        orientation: reads ``(roll, pitch, yaw)`` [deg] from an entry's orientation keys.
        on_object: called with each object that passed these checks, its entry and
            field (e.g. to claim its frame; it raises the :class:`SpecError`).
    """
    if "objects" not in top:
        return ()
    listed = reader.sequence(top["objects"], "objects", top.line_of("objects"))
    objects: list[ObjectSpec] = []
    for index, item in enumerate(listed):
        field = f"objects[{index}]"
        entry = reader.mapping(item, field, listed.line_of(index))
        spec = _object(reader, entry, field, base_dir, orientation)
        where = (entry.line_of("name"), f"{field}.name")
        if spec.name in arm_names:
            raise reader.error(*where, f"name {spec.name!r} is an arm's; names must be unique")
        if any(o.name == spec.name for o in objects):
            raise reader.error(*where, f"object name {spec.name!r} is used twice")
        if on_object is not None:
            on_object(spec, entry, field)
        objects.append(spec)
    return tuple(objects)


def _object(
    reader: SpecReader,
    entry: LocatedDict,
    field: str,
    base_dir: Path | None,
    orientation: Orientation,
) -> ObjectSpec:
    reader.only_keys(entry, field, OBJECT_KEYS)
    name = reader.text(entry, "name", field)
    shape = reader.text(entry, "shape", field)
    size: Any = None
    if "size_m" in entry:
        raw = entry["size_m"]
        if isinstance(raw, int | float) and not isinstance(raw, bool) and math.isfinite(raw):
            size = float(raw)
        else:
            size = reader.numbers(entry, "size_m", field, range(1, 10), "m")
    mesh = None
    if "mesh" in entry:
        given = Path(reader.text(entry, "mesh", field)).expanduser()
        mesh = given if given.is_absolute() or base_dir is None else base_dir / given
    try:
        return object_spec(
            name,
            shape,
            size=size,
            mass=reader.number(entry, "mass_kg", field, DEFAULT_MASS_KG, unit="kg"),
            friction=reader.number(entry, "friction", field, DEFAULT_FRICTION),
            spinning_friction=reader.number(
                entry, "spinning_friction_m", field, DEFAULT_SPINNING_FRICTION_M, unit="m"
            ),
            rolling_friction=reader.number(
                entry, "rolling_friction_m", field, DEFAULT_ROLLING_FRICTION_M, unit="m"
            ),
            color=_numbers_or(reader, entry, "color_rgba", field, 4, DEFAULT_COLOR),
            at=_numbers_or(reader, entry, "at_m", field, 3, (0.0, 0.0, 0.0)),
            rpy_deg=orientation(reader, entry, field),
            mesh=mesh,
            scale=reader.number(entry, "scale", field, 1.0),
        )
    except ObjectError as exc:
        if exc.field == "rpy_deg":
            key = next((k for k in ORIENTATION_KEYS if k in entry), "rpy_deg")
        else:
            key = _KEY_OF.get(exc.field, exc.field)
        raise reader.error(entry.line_of(key), f"{field}.{key}", exc.problem) from None


def _numbers_or(
    reader: SpecReader,
    entry: LocatedDict,
    key: str,
    field: str,
    length: int,
    default: tuple[float, ...],
) -> tuple[float, ...]:
    if key not in entry:
        return default
    return reader.numbers(entry, key, field, (length,), "m" if key.endswith("_m") else "")
