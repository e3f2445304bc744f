"""An :class:`ObjectSpec` as the keyword arguments that make it again.

:func:`armfleet.objects.object_spec` and :meth:`armfleet.World.add_object` take
the same arguments, so one mapping serves both: ``launch`` adds a spec's objects
with it, and the scene check re-checks with it an ``ObjectSpec`` that was built
by hand (the dataclass itself checks nothing).
"""

from __future__ import annotations

from typing import Any

from armfleet.objects.object_spec import ObjectSpec


def object_arguments(spec: ObjectSpec) -> dict[str, Any]:
    """Every argument after ``name`` and ``shape``, by keyword, for ``spec``."""
    return {
        "size": None if spec.mesh is not None else spec.size,  # a mesh's comes from its file
        "mass": spec.mass_kg,
        "friction": spec.friction,
        "spinning_friction": spec.spinning_friction_m,
        "rolling_friction": spec.rolling_friction_m,
        "color": spec.color,
        "at": spec.at,
        "rpy_deg": spec.rpy_deg,
        "mesh": spec.mesh,
        "scale": spec.scale,
    }
