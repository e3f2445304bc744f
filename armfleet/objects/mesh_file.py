"""Mesh files of scene objects (Wavefront OBJ, STL): checked and measured before loading.

PyBullet and MeshCat both read the file; reading its vertices and faces here
first turns a missing, empty, unreadable or faceless file (a lone vertex, which
PyBullet refuses with a bare ``pybullet.error``) into a clear error, and gives
the mesh's extents (the object's ``size``).

A mesh is also bounded in size, before PyBullet sees it: adding one stalls the world
it joins (every arm in it, and every live-API client sharing it) for as long as
PyBullet builds its collision shape. Measured on this project's 2-core machine
(static height fields, add_object only): 100k triangles 1.2 s and ~100 MB, 200k
triangles 2.3 s and ~170 MB (a moving one's convex hull: ~320 MB), 1M triangles
3.5 s (binary STL) to 8.5 s (OBJ) and 0.6-0.8 GB. :data:`MAX_MESH_TRIANGLES` keeps the
stall near 2 s; :data:`MAX_MESH_BYTES` bounds what is read to count them (an ASCII
STL of 200k triangles is ~50 MB; OBJ and binary STL are smaller).
"""

from __future__ import annotations

import itertools
import struct
from pathlib import Path

import numpy as np

from armfleet.checks.user_paths import file_problem
from armfleet.messages import FloatArray

MESH_SUFFIXES = (".obj", ".stl")
#: Most triangles a mesh object may have (see the module's measurements).
MAX_MESH_TRIANGLES = 200_000
#: Largest mesh file read [bytes]: 64 MiB.
MAX_MESH_BYTES = 64 * 2**20
_DECIMATE = "decimate it (e.g. MeshLab's quadric edge collapse or Blender's Decimate modifier)"
_STL_HEADER = 80
_STL_TRIANGLE = struct.Struct("<12fH")


def mesh_extents(path: Path) -> FloatArray:
    """Extents (x, y, z) [file units] of the bounding box of the mesh's vertices.

    Raises:
        ValueError: not a file, not .obj/.stl, without vertices, or without a
            face of non-zero area.
    """
    if path.suffix.lower() not in MESH_SUFFIXES:
        valid = ", ".join(MESH_SUFFIXES)
        raise ValueError(f"{path.name}: unsupported mesh file; use one of {valid}")
    problem = file_problem(path)
    if problem is not None:
        raise ValueError(f"mesh file {str(path)!r} {problem}")
    try:
        size = path.stat().st_size
        if size > MAX_MESH_BYTES:
            raise ValueError(
                f"mesh file {str(path)!r} is {size / 2**20:.0f} MiB, over the "
                f"{MAX_MESH_BYTES // 2**20} MiB limit for a mesh file; {_DECIMATE}"
            )
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"cannot read mesh file {str(path)!r}: {exc}") from None
    obj = path.suffix.lower() == ".obj"
    _check_triangles(path, _triangles_at_least(data, obj))  # before parsing them
    vertices, triangles = _obj_mesh(data) if obj else _stl_mesh(data)
    _check_triangles(path, len(triangles))  # an OBJ polygon is several triangles
    if len(vertices) == 0 or not np.isfinite(vertices).all():
        raise ValueError(f"mesh file {str(path)!r} has no (finite) vertices")
    extents: FloatArray = vertices.max(axis=0) - vertices.min(axis=0)
    if not _has_area(triangles, float(extents.max())):
        raise ValueError(
            f"mesh file {str(path)!r} has no face with an area ({len(vertices)} vertices, "
            f"{len(triangles)} triangles); a mesh needs triangles, not only points or lines"
        )
    return extents


def _check_triangles(path: Path, count: int) -> None:
    if count > MAX_MESH_TRIANGLES:
        raise ValueError(
            f"mesh file {str(path)!r} has {count:,} triangles, over the limit of "
            f"{MAX_MESH_TRIANGLES:,} (adding it would stall the world); {_DECIMATE}"
        )


def _triangles_at_least(data: bytes, obj: bool) -> int:
    """A cheap lower bound on the triangles in ``data``, counted without parsing it.

    A binary STL's header holds its count; an OBJ has a triangle or more per face
    line; an ASCII STL one per ``endfacet``.
    """
    if obj:
        return data.count(b"\nf ") + data.startswith(b"f ")
    if len(data) >= _STL_HEADER + 4:
        (count,) = struct.unpack_from("<I", data, _STL_HEADER)
        if len(data) == _STL_HEADER + 4 + count * _STL_TRIANGLE.size:  # binary STL
            return int(count)
    return data.count(b"endfacet")


def _has_area(triangles: FloatArray, size: float) -> bool:
    """Whether one of ``triangles`` (n x 3 corners x 3) is not degenerate at this size."""
    if len(triangles) == 0 or size <= 0.0:
        return False
    edges = triangles[:, 1:] - triangles[:, :1]
    areas = 0.5 * np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
    return bool(areas.max() > 1e-12 * size * size)


def _obj_mesh(data: bytes) -> tuple[FloatArray, FloatArray]:
    """Vertices (n x 3) and the faces' fan triangles (m x 3 x 3) of a Wavefront OBJ."""
    rows: list[list[float]] = []
    corners: list[tuple[int, int, int]] = []
    for line in data.decode("utf-8", errors="replace").splitlines():
        parts = line.split()
        if len(parts) >= 4 and parts[0] == "v":
            try:
                rows.append([float(x) for x in parts[1:4]])
            except ValueError:
                continue
        elif len(parts) >= 4 and parts[0] == "f":
            try:  # "f 1 2 3", "f 1/1/1 2/2/2 3/3/3"; negative indices count from the end
                index = [int(part.split("/")[0]) for part in parts[1:]]
            except ValueError:
                continue
            index = [i - 1 if i > 0 else len(rows) + i for i in index]
            if all(0 <= i < len(rows) for i in index):
                corners.extend((index[0], b, c) for b, c in itertools.pairwise(index[1:]))
    vertices = np.array(rows, dtype=float).reshape(-1, 3)
    return vertices, vertices[np.array(corners, dtype=int).reshape(-1, 3)]


def _stl_mesh(data: bytes) -> tuple[FloatArray, FloatArray]:
    """Vertices (n x 3) and triangles (m x 3 x 3) of a binary or ASCII STL."""
    if len(data) >= _STL_HEADER + 4:
        (count,) = struct.unpack_from("<I", data, _STL_HEADER)
        if len(data) == _STL_HEADER + 4 + count * _STL_TRIANGLE.size:  # binary STL
            triangles = np.frombuffer(
                data,
                dtype=np.dtype([("values", "<f4", 12), ("attribute", "<u2")]),
                count=count,
                offset=_STL_HEADER + 4,
            )
            corners = triangles["values"][:, 3:].reshape(-1, 3, 3).astype(float)
            return corners.reshape(-1, 3), corners
    rows = []
    for line in data.decode("ascii", errors="replace").splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[0] == "vertex":
            try:
                rows.append([float(x) for x in parts[1:]])
            except ValueError:
                continue
    vertices = np.array(rows, dtype=float).reshape(-1, 3)
    whole = len(vertices) - len(vertices) % 3
    return vertices, vertices[:whole].reshape(-1, 3, 3)
