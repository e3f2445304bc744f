"""msgpack frames and the bus's dataclass messages as plain maps and lists.

Only msgpack's plain types cross the wire (maps, lists, strings, numbers, bools,
nil): numpy arrays become lists of floats, enums their value, dataclasses maps of
their fields. Decoding rebuilds the dataclasses of :mod:`armfleet.messages` from
their type hints, so a new message type needs no change here.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import math
import typing
from collections.abc import Callable
from typing import Any

import msgpack  # type: ignore[import-untyped]
import numpy as np

from armfleet import messages
from armfleet.services.errors import ProtocolError
from armfleet.services.protocol import HARD_FRAME_LIMIT_BYTES, MAX_REQUEST_BYTES

Converter = Callable[[Any], Any]


def pack(value: Any) -> bytes:
    """One msgpack frame holding ``value`` (plain types only; see :func:`to_wire`)."""
    data: bytes = msgpack.packb(value, use_bin_type=True)
    return data


def unpack(data: bytes, limit: int = HARD_FRAME_LIMIT_BYTES) -> Any:
    """Read one msgpack frame of at most ``limit`` bytes, or raise :class:`ProtocolError`."""
    if len(data) > limit:
        raise ProtocolError(f"message of {len(data)} bytes exceeds the limit of {limit} bytes")
    try:
        return msgpack.unpackb(data, raw=False, strict_map_key=True)
    except Exception as exc:  # msgpack raises several kinds (ExtraData, FormatError, ...)
        detail = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
        if isinstance(exc, msgpack.StackError):
            detail = "nested too deeply"
        raise ProtocolError(f"not a valid msgpack message ({detail})") from None


def unpack_request(data: bytes) -> Any:
    """Read a request frame (at most :data:`MAX_REQUEST_BYTES`)."""
    if len(data) > MAX_REQUEST_BYTES:
        raise ProtocolError(
            f"request of {len(data)} bytes exceeds the limit of {MAX_REQUEST_BYTES} bytes"
        )
    return unpack(data, MAX_REQUEST_BYTES)


# -- messages to plain values ------------------------------------------------------------
def to_wire(value: Any) -> Any:
    """``value`` with dataclasses as maps, arrays as lists of floats, enums as their value."""
    if isinstance(value, np.ndarray):
        return value.astype(float).tolist() if value.dtype.kind != "b" else value.tolist()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _encoder(type(value))(value)
    if isinstance(value, enum.Enum):
        return to_wire(value.value)
    if isinstance(value, list | tuple):
        return [to_wire(item) for item in value]
    if isinstance(value, dict):
        return {str(key): to_wire(item) for key, item in value.items()}
    if isinstance(value, np.generic):
        return value.item()
    return value


@functools.cache
def _encoder(hint: Any) -> Converter:
    """A fast ``to_wire`` for values of type ``hint`` (messages are sent thousands of
    times a second: the field types are read once)."""
    origin = typing.get_origin(hint)
    if hint in (float, int, str, bool):
        return _same
    if origin is np.ndarray or hint is np.ndarray:
        return _array_to_list
    if origin is tuple:
        args = typing.get_args(hint)
        if all(a in (float, int, str, bool, Ellipsis) for a in args):
            return list
        return to_wire
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        hints = typing.get_type_hints(hint)
        fields = [(f.name, _encoder(hints[f.name])) for f in dataclasses.fields(hint)]
        return lambda value: {name: encode(getattr(value, name)) for name, encode in fields}
    return to_wire


def _same(value: Any) -> Any:
    return value


def _array_to_list(value: Any) -> Any:
    if isinstance(value, np.ndarray) and value.dtype == np.float64:
        return value.tolist()
    return to_wire(value)


# -- plain values to messages ------------------------------------------------------------
@functools.cache
def message_types() -> dict[str, type]:
    """The bus's message types by name, read from :mod:`armfleet.messages`."""
    return {
        name: value
        for name, value in vars(messages).items()
        if isinstance(value, type) and dataclasses.is_dataclass(value)
    }


def decode_message(type_name: str, data: Any) -> Any:
    """Rebuild a message of :mod:`armfleet.messages` from its map.

    A type this side does not know (a newer world) is returned as the plain map.
    """
    cls = message_types().get(type_name)
    if cls is None:
        return data
    try:
        return _converter(cls)(data)
    except (TypeError, ValueError, KeyError) as exc:
        raise ProtocolError(f"malformed {type_name} message: {exc}") from None


@functools.cache
def _converter(hint: Any) -> Converter:
    origin = typing.get_origin(hint)
    if hint is float:
        return _to_float
    if hint in (int, str, bool):
        return functools.partial(_checked, hint)
    if origin is np.ndarray or hint is np.ndarray:
        return _to_array
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return hint
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return _dataclass_converter(hint)
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            item = _converter(args[0])
            return lambda values: tuple(item(v) for v in _as_list(values))
        items = [_converter(a) for a in args]
        return lambda values: tuple(
            convert(v) for convert, v in zip(items, _as_list(values), strict=True)
        )
    return lambda value: value


def _dataclass_converter(cls: type) -> Converter:
    hints = typing.get_type_hints(cls)
    fields = [(f.name, _converter(hints[f.name])) for f in dataclasses.fields(cls)]

    def convert(data: Any) -> Any:
        if not isinstance(data, dict):
            raise TypeError(f"{cls.__name__} must be a map, got {type(data).__name__}")
        return cls(**{name: convert_field(data[name]) for name, convert_field in fields})

    return convert


def _as_list(values: Any) -> list[Any]:
    if not isinstance(values, list):
        raise TypeError(f"expected a list, got {type(values).__name__}")
    return values


def _to_float(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"expected a number, got {type(value).__name__}")
    return float(value)


def _to_array(values: Any) -> Any:
    return np.asarray(_as_list(values), dtype=np.float64)


def _checked(kind: type, value: Any) -> Any:
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        raise TypeError(f"expected {kind.__name__}, got {type(value).__name__}")
    return value


def is_finite_number(value: Any) -> bool:
    """A msgpack number that is finite (bools are not numbers here)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
