"""Mesh files of scene objects (Wavefront OBJ, STL): checked and measured before loading.

PyBullet and MeshCat both read the file; reading its vertices here first turns
a missing, empty or unreadable file into a clear error, and gives the mesh's
extents (the object's ``size``).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from armfleet.messages import FloatArray

MESH_SUFFIXES = (".obj", ".stl")
_STL_HEADER = 80
_STL_TRIANGLE = struct.Struct("<12fH")


def mesh_extents(path: Path) -> FloatArray:
    """Extents (x, y, z) [file units] of the bounding box of the mesh's vertices.

    Raises:
        ValueError: not a file, not .obj/.stl, or without vertices.
    """
    if path.suffix.lower() not in MESH_SUFFIXES:
        valid = ", ".join(MESH_SUFFIXES)
        raise ValueError(f"{path.name}: unsupported mesh file; use one of {valid}")
    if not path.is_file():
        raise ValueError(f"mesh file {str(path)!r} not found")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"cannot read mesh file {str(path)!r}: {exc}") from None
    vertices = _obj_vertices(data) if path.suffix.lower() == ".obj" else _stl_vertices(data)
    if len(vertices) == 0 or not np.isfinite(vertices).all():
        raise ValueError(f"mesh file {str(path)!r} has no (finite) vertices")
    extents: FloatArray = vertices.max(axis=0) - vertices.min(axis=0)
    return extents


def _obj_vertices(data: bytes) -> FloatArray:
    rows = []
    for line in data.decode("utf-8", errors="replace").splitlines():
        parts = line.split()
        if len(parts) >= 4 and parts[0] == "v":
            try:
                rows.append([float(x) for x in parts[1:4]])
            except ValueError:
                continue
    return np.array(rows, dtype=float).reshape(-1, 3)


def _stl_vertices(data: bytes) -> FloatArray:
    if len(data) >= _STL_HEADER + 4:
        (count,) = struct.unpack_from("<I", data, _STL_HEADER)
        if len(data) == _STL_HEADER + 4 + count * _STL_TRIANGLE.size:  # binary STL
            triangles = np.frombuffer(
                data,
                dtype=np.dtype([("values", "<f4", 12), ("attribute", "<u2")]),
                count=count,
                offset=_STL_HEADER + 4,
            )
            return triangles["values"][:, 3:].reshape(-1, 3).astype(float)
    rows = []
    for line in data.decode("ascii", errors="replace").splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[0] == "vertex":
            try:
                rows.append([float(x) for x in parts[1:]])
            except ValueError:
                continue
    return np.array(rows, dtype=float).reshape(-1, 3)
