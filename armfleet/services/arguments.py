"""Checked access to the ``args`` map of a request: missing, unknown or mistyped fields
are a :class:`ProtocolError` naming the field and what it should be."""

from __future__ import annotations

import math
from collections.abc import Collection
from typing import Any

from armfleet.checks.number_ranges import NumberRange
from armfleet.services.errors import ProtocolError

_MISSING = object()


class Arguments:
    """The arguments of one request of ``service``.

    Args:
        service: the service name, for messages.
        raw: the decoded ``args`` value.
        fields: every field the service accepts.
    """

    def __init__(
        self, service: str, raw: Any, fields: Collection[str], *, label: str = "'args'"
    ) -> None:
        self._service = service
        if raw is None:
            raw = {}
        if not isinstance(raw, dict):
            raise ProtocolError(f"{service}: {label} must be a map, got {_kind(raw)}")
        unknown = sorted(set(raw) - set(fields))
        if unknown:
            valid = ", ".join(sorted(fields)) or "(none)"
            raise ProtocolError(f"{service}: unknown field {unknown[0]!r}; fields: {valid}")
        self._raw: dict[str, Any] = raw

    def has(self, key: str) -> bool:
        return self._raw.get(key) is not None

    def raw(self, key: str) -> Any:
        """The field as sent (None if absent), unchecked."""
        return self._raw.get(key)

    def keys(self) -> list[str]:
        return list(self._raw)

    def _get(self, key: str, default: Any) -> Any:
        value = self._raw.get(key)
        if value is None:
            if default is _MISSING:
                raise ProtocolError(f"{self._service}: missing field {key!r}")
            return default
        return value

    def text(self, key: str, default: Any = _MISSING) -> Any:
        """A string field (``default`` if absent; required without one)."""
        value = self._get(key, default)
        if value is not default and not isinstance(value, str):
            raise ProtocolError(f"{self._service}: {key!r} must be a string, got {_kind(value)}")
        return value

    def number(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        low: float = -math.inf,
        high: float = math.inf,
        finite: bool = True,
    ) -> Any:
        """A finite number in ``[low, high]`` (any number if not ``finite``: the world
        then names the problem in its own words)."""
        value = self._get(key, default)
        if value is default:
            return value
        if not _is_number(value):
            raise ProtocolError(f"{self._service}: {key!r} must be a number, got {_kind(value)}")
        if finite and not (math.isfinite(value) and low <= value <= high):
            raise ProtocolError(
                f"{self._service}: {key!r} is {value}; it must be a finite number in "
                f"[{low:g}, {high:g}]"
            )
        return float(value)

    def in_range(self, key: str, default: Any, valid: NumberRange) -> Any:
        """A number in one of the ranges of :mod:`armfleet.checks.number_ranges` (the same
        range the command line checks); ``default`` if absent (required if ``_MISSING``)."""
        value = self._get(key, default)
        if value is default:
            return value
        if not valid.contains(value):
            raise ProtocolError(f"{self._service}: {key!r} is {value!r}; give {valid.valid}")
        return int(value) if valid.integer else float(value)

    def flag(self, key: str, default: Any = _MISSING) -> Any:
        """A bool."""
        value = self._get(key, default)
        if value is not default and not isinstance(value, bool):
            raise ProtocolError(
                f"{self._service}: {key!r} must be true or false, got {_kind(value)}"
            )
        return value

    def integer(self, key: str, default: Any = _MISSING, *, low: int, high: int) -> Any:
        """An integer in ``[low, high]``."""
        value = self._get(key, default)
        if value is default:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            raise ProtocolError(f"{self._service}: {key!r} must be an integer, got {_kind(value)}")
        if not low <= value <= high:
            raise ProtocolError(f"{self._service}: {key!r} is {value}; give {low}..{high}")
        return value

    def vector(self, key: str, default: Any = _MISSING) -> Any:
        """A flat list of numbers (non-finite values pass: the world names the joint)."""
        value = self._get(key, default)
        if value is default:
            return value
        if not isinstance(value, list) or not all(_is_number(v) for v in value):
            raise ProtocolError(
                f"{self._service}: {key!r} must be a list of numbers, got {_describe(value)}"
            )
        return [float(v) for v in value]

    def mapping(self, key: str, default: Any = _MISSING) -> Any:
        value = self._get(key, default)
        if value is not default and not isinstance(value, dict):
            raise ProtocolError(f"{self._service}: {key!r} must be a map, got {_kind(value)}")
        return value


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _kind(value: Any) -> str:
    names = {dict: "a map", list: "a list", str: "a string", bytes: "bytes", bool: "a bool"}
    return names.get(type(value), type(value).__name__)


def _describe(value: Any) -> str:
    if isinstance(value, list):
        odd = next((v for v in value if not _is_number(v)), None)
        return f"a list holding {_kind(odd)}" if odd is not None else "a list"
    return _kind(value)
