"""What a scene object is made of: shape, size, mass, friction, colour and pose, all checked.

The one place that validates an object: :meth:`armfleet.World.add_object` and
the launch spec loader both build an :class:`ObjectSpec` with
:func:`object_spec`, so both accept and reject the same things.
"""

from __future__ import annotations

import enum
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from armfleet.checks.names import RESERVED_NAMES, name_problem
from armfleet.checks.number_ranges import ANGLE_DEG, WORLD_COORDINATE_M
from armfleet.checks.real_numbers import is_real, is_real_vector
from armfleet.errors import ObjectError
from armfleet.messages import FloatArray
from armfleet.objects.mesh_file import MESH_SUFFIXES, mesh_extents

#: Lateral (Coulomb) friction coefficient of an object unless given.
DEFAULT_FRICTION = 0.8
#: Torsional friction [m]: resists spinning about the contact normal, so a box held
#: between two fingers does not turn out of the grasp. Bullet multiplies it by the
#: other body's lateral friction.
DEFAULT_SPINNING_FRICTION_M = 0.005
#: Rolling resistance [m]: a ball or a cylinder on its side rolls to a stop.
DEFAULT_ROLLING_FRICTION_M = 0.0002
#: Mass of an object unless given [kg]: something an arm can pick up.
DEFAULT_MASS_KG = 0.1
DEFAULT_COLOR = (0.85, 0.55, 0.2, 1.0)
#: Largest size of an object [m] and mass [kg] accepted: beyond is a typo.
MAX_SIZE_M = 100.0
MAX_MASS_KG = 10_000.0


class Shape(enum.Enum):
    """Shape of a scene object."""

    BOX = "box"
    CYLINDER = "cylinder"
    SPHERE = "sphere"
    MESH = "mesh"


#: What ``size`` means per shape, for the error messages.
SIZE_MEANING = {
    Shape.BOX: "(x, y, z) full extents",
    Shape.CYLINDER: "(radius, length), axis along the object's z",
    Shape.SPHERE: "(radius,)",
}
_SIZE_LENGTH = {Shape.BOX: 3, Shape.CYLINDER: 2, Shape.SPHERE: 1}


@dataclass(frozen=True)
class ObjectSpec:
    """A checked scene object.

    The object's frame is the centre of a box, cylinder or sphere (a cylinder's
    axis is its z), and the mesh file's origin for a mesh.

    Attributes:
        name: object name (as an arm name), also its ``/tf`` frame.
        shape: its shape.
        size: box (x, y, z) full extents; cylinder (radius, length); sphere
            (radius,); mesh: extents of the scaled mesh's bounding box [m].
        mass_kg: mass [kg]; 0 makes it static, fixed in the world (a table).
        friction: lateral friction coefficient.
        spinning_friction_m: torsional friction [m].
        rolling_friction_m: rolling friction [m].
        color: RGBA, each in [0, 1].
        at: position of the object's frame in the world [m].
        rpy_deg: orientation, roll, pitch, yaw [deg] (R = Rz(yaw) Ry(pitch) Rx(roll)).
        mesh: absolute path of the .obj/.stl file (mesh only).
        scale: scale applied to the mesh file's coordinates.
    """

    name: str
    shape: Shape
    size: tuple[float, ...]
    mass_kg: float = DEFAULT_MASS_KG
    friction: float = DEFAULT_FRICTION
    spinning_friction_m: float = DEFAULT_SPINNING_FRICTION_M
    rolling_friction_m: float = DEFAULT_ROLLING_FRICTION_M
    color: tuple[float, float, float, float] = DEFAULT_COLOR
    at: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mesh: Path | None = None
    scale: float = 1.0

    @property
    def is_static(self) -> bool:
        """Whether it is fixed in the world (mass 0)."""
        return self.mass_kg == 0.0

    @property
    def half_extents(self) -> FloatArray:
        """Half extents [m] of a box about the object's origin holding it, in its own frame.

        For a mesh, whose origin may lie anywhere in its bounding box, the full
        extents (a conservative box).
        """
        if self.shape is Shape.MESH:
            return np.asarray(self.size, dtype=float)
        if self.shape is Shape.SPHERE:
            return np.full(3, self.size[0])
        if self.shape is Shape.CYLINDER:
            return np.array([self.size[0], self.size[0], self.size[1] / 2])
        return np.asarray(self.size, dtype=float) / 2

    def matrix(self) -> FloatArray:
        """4x4 pose of the object in the world at ``at``, ``rpy_deg``."""
        return pose_matrix(self.at, self.rpy_deg)


def pose_matrix(at: Sequence[float], rpy_deg: Sequence[float]) -> FloatArray:
    """4x4 pose from a position [m] and roll, pitch, yaw [deg] (R = Rz Ry Rx)."""
    roll, pitch, yaw = (math.radians(a) for a in rpy_deg)
    cr, sr, cp, sp, cy, sy = (
        math.cos(roll),
        math.sin(roll),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(yaw),
        math.sin(yaw),
    )
    matrix = np.eye(4)
    matrix[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    matrix[:3, 3] = at
    return matrix


def check_object_name(name: object) -> str:
    """``name`` if it is a well-formed object name (the arm-name rule, not reserved)."""
    problem = name_problem(name)
    if problem is not None:
        raise ObjectError(name, "name", problem)
    assert isinstance(name, str)  # name_problem checked it
    if name in RESERVED_NAMES:
        raise ObjectError(name, "name", f"reserved; names may not be {', '.join(RESERVED_NAMES)}")
    return name


def object_spec(
    name: str,
    shape: str | Shape,
    *,
    size: float | Sequence[float] | None = None,
    mass: float = DEFAULT_MASS_KG,
    friction: float = DEFAULT_FRICTION,
    spinning_friction: float = DEFAULT_SPINNING_FRICTION_M,
    rolling_friction: float = DEFAULT_ROLLING_FRICTION_M,
    color: Sequence[float] = DEFAULT_COLOR,
    at: Sequence[float] = (0.0, 0.0, 0.0),
    rpy_deg: Sequence[float] = (0.0, 0.0, 0.0),
    mesh: str | Path | None = None,
    scale: float = 1.0,
) -> ObjectSpec:
    """Check every argument and return the object; see :meth:`armfleet.World.add_object`.

    Raises:
        ObjectError: naming the argument, the problem and what is valid.
    """
    check_object_name(name)
    kind = _shape(name, shape)

    def fail(field: str, problem: str) -> ObjectError:
        return ObjectError(name, field, problem)

    mass_kg = _number(name, "mass", mass, 0.0, MAX_MASS_KG, "kg (0: static)")
    friction = _number(name, "friction", friction, 0.0, 10.0, "(coefficient)")
    spinning = _number(name, "spinning_friction", spinning_friction, 0.0, 1.0, "m")
    rolling = _number(name, "rolling_friction", rolling_friction, 0.0, 1.0, "m")
    rgba = _numbers(name, "color", color, 4, "RGBA")
    if not all(0.0 <= c <= 1.0 for c in rgba):
        raise fail("color", f"{list(rgba)} has a value outside [0, 1]; give RGBA in [0, 1]")
    position = _numbers(name, "at", at, 3, "(x, y, z) [m]")
    rpy = _numbers(name, "rpy_deg", rpy_deg, 3, "(roll, pitch, yaw) [deg]")
    for field, values, valid in (("at", position, WORLD_COORDINATE_M), ("rpy_deg", rpy, ANGLE_DEG)):
        if not all(valid.contains(v) for v in values):
            raise fail(field, f"{list(values)} is out of range; give {valid.valid} each")
    scale = _number(name, "scale", scale, 1e-6, 1e6, "")
    path: Path | None = None
    if kind is Shape.MESH:
        if mesh is None:
            raise fail("mesh", f"a mesh object needs mesh=<path to a {'/'.join(MESH_SUFFIXES)}>")
        if size is not None:
            raise fail("size", "a mesh's size comes from its file; give scale instead")
        if not isinstance(mesh, str | os.PathLike):
            raise fail("mesh", f"{mesh!r} is not a path; give a {'/'.join(MESH_SUFFIXES)} file")
        path = Path(mesh).expanduser().resolve()
        try:
            extents = mesh_extents(path)
        except ValueError as exc:
            raise fail("mesh", str(exc)) from None
        dimensions = tuple(float(e) * scale for e in extents)
        if mass_kg > 0.0 and min(dimensions) <= 0.0:
            raise fail(
                "mesh",
                f"{path.name} is flat (extents {list(dimensions)} m); a moving mesh collides "
                "as its convex hull and needs a volume (mass=0 keeps it static)",
            )
    else:
        if mesh is not None:
            raise fail("mesh", f"only a mesh object takes a mesh file, not a {kind.value}")
        if scale != 1.0:
            raise fail("scale", f"only a mesh object is scaled; give a {kind.value}'s size")
        dimensions = _size(name, kind, size)
    return ObjectSpec(
        name=name,
        shape=kind,
        size=dimensions,
        mass_kg=mass_kg,
        friction=friction,
        spinning_friction_m=spinning,
        rolling_friction_m=rolling,
        color=(rgba[0], rgba[1], rgba[2], rgba[3]),
        at=(position[0], position[1], position[2]),
        rpy_deg=(rpy[0], rpy[1], rpy[2]),
        mesh=path,
        scale=scale,
    )


def _shape(name: str, shape: str | Shape) -> Shape:
    if isinstance(shape, Shape):
        return shape
    try:
        return Shape(shape)
    except ValueError:
        valid = ", ".join(s.value for s in Shape)
        raise ObjectError(name, "shape", f"unknown shape {shape!r}; valid: {valid}") from None


def _size(name: str, kind: Shape, size: float | Sequence[float] | None) -> tuple[float, ...]:
    expected = _SIZE_LENGTH[kind]
    meaning = f"a {kind.value} takes {SIZE_MEANING[kind]} [m]"
    if size is None:
        raise ObjectError(name, "size", f"required; {meaning}")
    values: Any = (size,) if is_real(size) else size
    if not is_real_vector(values):
        raise ObjectError(name, "size", f"{size!r} is not numbers; {meaning}")
    numbers = tuple(float(v) for v in values)
    if len(numbers) != expected:
        raise ObjectError(name, "size", f"got {len(numbers)} numbers; {meaning}")
    if not all(math.isfinite(v) and 0.0 < v <= MAX_SIZE_M for v in numbers):
        raise ObjectError(
            name, "size", f"{list(numbers)}: each must be in (0, {MAX_SIZE_M:g}] m; {meaning}"
        )
    return numbers


def _number(name: str, field: str, value: Any, lower: float, upper: float, unit: str) -> float:
    if not is_real(value):
        raise ObjectError(name, field, f"expected a number {unit}, got {value!r}".rstrip())
    number = float(value)
    if not (math.isfinite(number) and lower <= number <= upper):
        raise ObjectError(name, field, f"{number} is outside [{lower:g}, {upper:g}] {unit}".strip())
    return number


def _numbers(name: str, field: str, value: Any, length: int, meaning: str) -> tuple[float, ...]:
    if not is_real_vector(value):
        raise ObjectError(name, field, f"expected {length} numbers {meaning}, got {value!r}")
    numbers = tuple(float(v) for v in value)
    if len(numbers) != length or not all(math.isfinite(v) for v in numbers):
        raise ObjectError(
            name, field, f"expected {length} finite numbers {meaning}, got {list(numbers)}"
        )
    return numbers
