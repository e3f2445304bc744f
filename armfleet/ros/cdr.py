"""The streamed messages (``/tf``, joint states) serialized straight to CDR bytes.

Building rclpy message objects costs ~150 µs for one arm's nine transforms, and rclpy's
serializer ~75 µs more: at 100 instants per simulated second and 30 arms, most of a
step. A message's layout depends only on its frame or joint names, fixed per arm, so
each layout is laid out once (:class:`TfLayout`, :class:`JointStateLayout`); then only
the stamps and numbers are written into a copy (a few µs). ``rclpy``'s ``publish``
takes the bytes as they are (``publish_raw``).

The encoding is ROS 2's: plain CDR, little endian (encapsulation ``00 01 00 00``),
each primitive aligned to its size from the start of the payload, strings with their
length (NUL included) first. ``tests/test_ros_cdr.py`` checks the bytes are the ones
rclpy's own serializer gives, byte for byte.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from armfleet.messages import FloatArray, JointState, TFMessage

_HEADER = b"\x00\x01\x00\x00"  # CDR, little endian
_NS = 1_000_000_000


class _Writer:
    """Appends CDR fields to a payload, recording where the variable ones go."""

    def __init__(self) -> None:
        self.data = bytearray(_HEADER)

    @property
    def offset(self) -> int:
        return len(self.data)

    def align(self, size: int) -> None:
        self.data.extend(b"\x00" * (-(len(self.data) - len(_HEADER)) % size))

    def u32(self, value: int) -> None:
        self.align(4)
        self.data.extend(struct.pack("<I", value))

    def string(self, text: str) -> None:
        encoded = text.encode()
        self.u32(len(encoded) + 1)
        self.data.extend(encoded + b"\x00")

    def stamp(self) -> int:
        """Room for a ``builtin_interfaces/Time``; its offset."""
        self.align(4)
        offset = self.offset
        self.data.extend(b"\x00" * 8)
        return offset

    def doubles(self, count: int) -> int:
        """Room for ``count`` float64; the offset of the first."""
        self.align(8)
        offset = self.offset
        self.data.extend(b"\x00" * (8 * count))
        return offset


def _split(seconds: float) -> tuple[int, int]:
    total = round(seconds * _NS)
    return total // _NS, total % _NS


class TfLayout:
    """``tf2_msgs/TFMessage`` of a fixed list of (parent, child) frames."""

    def __init__(self, frames: Sequence[tuple[str, str]]) -> None:
        writer = _Writer()
        writer.u32(len(frames))
        self._stamps: list[int] = []
        self._values: list[int] = []
        for parent, child in frames:
            self._stamps.append(writer.stamp())
            writer.string(parent)
            writer.string(child)
            self._values.append(writer.doubles(7))  # translation xyz, rotation xyzw
        self._template = bytes(writer.data)

    def serialize(self, message: TFMessage) -> bytes:
        data = bytearray(self._template)
        for transform, stamp_at, values_at in zip(
            message.transforms, self._stamps, self._values, strict=True
        ):
            matrix = np.asarray(transform.matrix, dtype=float)
            x, y, z, w = pin.Quaternion(matrix[:3, :3]).normalized().coeffs()
            struct.pack_into("<iI", data, stamp_at, *_split(transform.stamp))
            struct.pack_into(
                "<7d", data, values_at, matrix[0, 3], matrix[1, 3], matrix[2, 3], x, y, z, w
            )
        return bytes(data)


class JointStateLayout:
    """``sensor_msgs/JointState`` of a fixed list of joint names (frame_id empty)."""

    def __init__(self, names: Sequence[str]) -> None:
        writer = _Writer()
        self._stamp = writer.stamp()
        writer.string("")  # header.frame_id
        writer.u32(len(names))
        for name in names:
            writer.string(name)
        self._arrays: list[int] = []
        for _ in range(3):  # position, velocity, effort
            writer.u32(len(names))
            self._arrays.append(writer.doubles(len(names)) if names else writer.offset)
        self._count = len(names)
        self._template = bytes(writer.data)

    def serialize(self, state: JointState) -> bytes:
        data = bytearray(self._template)
        struct.pack_into("<iI", data, self._stamp, *_split(state.stamp))
        arrays: tuple[FloatArray, ...] = (state.position, state.velocity, state.effort)
        for values, offset in zip(arrays, self._arrays, strict=True):
            if len(values) != self._count:
                raise ValueError(f"{len(values)} values for {self._count} joints")
            data[offset : offset + 8 * self._count] = np.asarray(values, "<f8").tobytes()
        return bytes(data)
