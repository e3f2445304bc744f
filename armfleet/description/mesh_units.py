"""The length unit a mesh file declares: COLLADA's ``<asset><unit meter="..."/>``.

PyBullet applies it (a mesh in centimetres collides at its size in metres), and so does
the viewer; coal's mesh loader, which builds the planner's geometry through Pinocchio,
does not (measured: a ``<unit meter="0.01"/>`` cube loads 100 times too large). The
planner scales such meshes by :func:`mesh_unit_m` itself. STL and OBJ declare no unit:
metres.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path


def mesh_unit_m(path: str | Path) -> float:
    """Metres per unit of the mesh file at ``path``: COLLADA's declared unit, else 1."""
    file = Path(path)
    if file.suffix.lower() != ".dae":
        return 1.0
    try:
        for _, element in ET.iterparse(file, events=("start",)):
            if element.tag.rsplit("}", 1)[-1] == "unit":
                unit = float(element.get("meter", "1"))
                return unit if unit > 0.0 else 1.0
            if element.tag.rsplit("}", 1)[-1].startswith("library_"):
                break  # <asset> comes first: past it, no unit is declared
    except (OSError, ET.ParseError, ValueError):
        return 1.0  # unreadable files are refused before any planner sees them
    return 1.0
