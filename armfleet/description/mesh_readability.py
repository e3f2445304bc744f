"""Whether PyBullet can read a robot description's mesh file: a cheap look at its bytes.

PyBullet does not refuse a mesh it cannot read: measured with PyBullet 3.2, an empty or
garbage ``.stl``, ``.dae`` or ``.obj`` loads as a link with no shape at all (no collision:
arms pass through it), an ASCII STL or a binary STL with bytes after its triangles too,
and a COLLADA file with no geometry crashes the process (segmentation fault). So each
mesh a description names is looked at before PyBullet sees it:

- **STL**: binary, exactly 84 bytes of header and count plus 50 bytes per triangle, at
  least one triangle (PyBullet reads no ASCII STL; the viewer does, so ASCII is refused
  for collision shapes only);
- **COLLADA** (``.dae``): XML with a ``<mesh>`` holding a ``<float_array>`` of
  positions and a primitive (``<triangles>``, ``<polylist>`` ...) with indices ``<p>``;
- **OBJ**: at least three ``v`` lines and one ``f`` line.

Scale is PyBullet's to apply and it does: a COLLADA ``<unit meter="0.01"/>`` and a
URDF ``<mesh scale="...">`` both give the collision shape its scaled size (measured:
``tests/test_check_model.py``), so nothing is rewritten for them.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

#: Mesh formats PyBullet reads, by file suffix (lower case).
MESH_SUFFIXES = (".stl", ".dae", ".obj")
_STL_HEADER_BYTES = 84
_STL_TRIANGLE_BYTES = 50
_DAE_PRIMITIVES = ("triangles", "polylist", "polygons", "trifans", "tristrips")
_OBJ_VERTEX = re.compile(rb"^v\s", re.MULTILINE)
_OBJ_FACE = re.compile(rb"^f\s", re.MULTILINE)


def mesh_problem(path: Path, collision: bool) -> str | None:
    """What keeps PyBullet from reading the mesh at ``path`` (an existing file), or None.

    Args:
        path: the mesh file.
        collision: it gives a collision shape (PyBullet must read it), not only a visual.
    """
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        return f"is a {suffix or 'suffix-less'} file; PyBullet reads {', '.join(MESH_SUFFIXES)}"
    try:
        data = path.read_bytes()
    except OSError as exc:
        return f"cannot be read ({exc.strerror})"
    if not data.strip():
        return "is empty"
    if suffix == ".stl":
        return _stl_problem(data, collision)
    if suffix == ".obj":
        return _obj_problem(data)
    return _dae_problem(data)


def _stl_problem(data: bytes, collision: bool) -> str | None:
    if len(data) >= _STL_HEADER_BYTES:
        count = int.from_bytes(data[80:84], "little")
        if count > 0 and len(data) == _STL_HEADER_BYTES + _STL_TRIANGLE_BYTES * count:
            return None
    if data.lstrip().startswith(b"solid") and b"vertex" in data:
        if not collision:
            return None  # the viewer reads it; PyBullet only loads visuals it can
        return (
            "is an ASCII STL, which PyBullet does not read (no collision shape); "
            "save it as binary STL"
        )
    return f"is no STL PyBullet reads ({len(data)} bytes: not 84 header bytes plus 50 per triangle)"


def _obj_problem(data: bytes) -> str | None:
    vertices, faces = len(_OBJ_VERTEX.findall(data)), len(_OBJ_FACE.findall(data))
    if vertices >= 3 and faces >= 1:
        return None
    return f"is no Wavefront OBJ mesh ({vertices} 'v' and {faces} 'f' lines)"


def _dae_problem(data: bytes) -> str | None:
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        return f"is no COLLADA file (not XML: {exc})"
    for mesh in root.iter():
        if _local(mesh.tag) != "mesh":
            continue
        positions = any(
            _local(e.tag) == "float_array" and (e.text or "").strip() for e in mesh.iter()
        )
        primitive = any(
            _local(e.tag) in _DAE_PRIMITIVES
            and any(_local(p.tag) == "p" and (p.text or "").strip() for p in e)
            for e in mesh
        )
        if positions and primitive:
            return None
    return "is a COLLADA file with no mesh geometry (no <mesh> with positions and triangles)"


def _local(tag: str) -> str:
    """``tag`` without its XML namespace (COLLADA's ``{http://www.collada.org/...}``)."""
    return tag.rpartition("}")[2]
