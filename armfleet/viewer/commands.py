"""MeshCat commands as msgpack bytes, built fast for live updates.

A live update is a set of :data:`Update` entries keyed by what they set, so a
newer value of the same thing replaces an older one that was not sent yet.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
import umsgpack

#: (command type, node path, property name or b"") of one live update.
UpdateKey = tuple[bytes, bytes, bytes]
#: The latest msgpack-encoded command for each key.
Updates = dict[UpdateKey, bytes]

SET_TRANSFORM = b"set_transform"
SET_PROPERTY = b"set_property"

_FLOAT64 = 0xCB  # msgpack's marker of a big-endian float64
_MATRIX_ENTRY = np.dtype([("marker", "u1"), ("value", ">f8")])
_MATRIX_BYTES = 16 * _MATRIX_ENTRY.itemsize


def property_command(path: str, name: str, value: Any) -> tuple[UpdateKey, bytes]:
    """A ``set_property`` update."""
    data = {"type": "set_property", "path": path, "property": name, "value": value}
    return (SET_PROPERTY, path.encode(), name.encode()), umsgpack.packb(data)


class TransformPacker:
    """Packs 4x4 poses of fixed nodes into ``set_transform`` commands.

    The bytes before the matrix are built once per node; packing a pose is
    then a numpy copy.

    Args:
        paths: MeshCat paths of the nodes, e.g. ``/meshcat/armfleet/bob/visuals/...``.
    """

    def __init__(self, paths: Sequence[str]) -> None:
        self.paths = tuple(paths)
        self._keys: list[UpdateKey] = [(SET_TRANSFORM, p.encode(), b"") for p in self.paths]
        self._heads: list[bytes] = []
        for path in self.paths:
            packed = umsgpack.packb({"type": "set_transform", "path": path, "matrix": [0.0] * 16})
            head, tail = packed[:-_MATRIX_BYTES], packed[-_MATRIX_BYTES:]
            if tail != (bytes([_FLOAT64]) + bytes(8)) * 16:
                raise RuntimeError("unexpected msgpack layout of a set_transform command")
            self._heads.append(head)
        self._entries = np.empty((len(self.paths), 16), dtype=_MATRIX_ENTRY)
        self._entries["marker"] = _FLOAT64

    def pack(self, poses: npt.NDArray[np.float64], into: Updates) -> None:
        """Add the commands placing each node at ``poses[i]`` (n x 4 x 4, world) to ``into``."""
        # MeshCat (three.js) reads matrices column by column.
        self._entries["value"] = poses.transpose(0, 2, 1).reshape(len(self.paths), 16)
        body = self._entries.tobytes()
        for i, (key, head) in enumerate(zip(self._keys, self._heads, strict=True)):
            into[key] = head + body[i * _MATRIX_BYTES : (i + 1) * _MATRIX_BYTES]
