"""Typed, located reading of spec fields: each problem becomes a SpecError at its line."""

from __future__ import annotations

import difflib
import math
from collections.abc import Collection, Sequence
from typing import Any

from armfleet.checks.located_yaml import LocatedDict, LocatedList
from armfleet.spec.spec_error import SpecError

_MISSING = object()
#: Longest text a spec field takes (a path can be 4096 bytes long on Linux) [characters].
MAX_TEXT_CHARS = 4096
#: Longest value repeated in an error message; longer ones are cut [characters].
SHOWN_CHARS = 40


class SpecReader:
    """Reads fields of one spec source, raising :class:`SpecError` with file and line."""

    def __init__(self, source: str) -> None:
        self.source = source

    def error(self, line: int, field: str, problem: str) -> SpecError:
        return SpecError(self.source, line, field, problem)

    def mapping(self, value: Any, field: str, line: int) -> LocatedDict:
        if not isinstance(value, LocatedDict):
            raise self.error(line, field, f"expected a mapping (key: value), got {_kind(value)}")
        return value

    def sequence(self, value: Any, field: str, line: int) -> LocatedList:
        if not isinstance(value, LocatedList):
            raise self.error(line, field, f"expected a list, got {_kind(value)}")
        return value

    def only_keys(self, mapping: LocatedDict, field: str, allowed: Collection[str]) -> None:
        """Reject keys not in ``allowed``, suggesting the closest valid one."""
        for key in mapping:
            if key not in allowed:
                # A key missing only its unit ("yaw" for "yaw_deg") gets the first unit offered.
                with_unit = [name for name in allowed if name.startswith(f"{key}_")]
                close = with_unit or difflib.get_close_matches(key, allowed, n=1, cutoff=0.5)
                hint = f"did you mean '{close[0]}'? " if close else ""
                raise self.error(
                    mapping.line_of(key),
                    _join(field, key),
                    f"unknown key; {hint}valid keys: {', '.join(sorted(allowed))}",
                )

    def number(
        self,
        mapping: LocatedDict,
        key: str,
        field: str,
        default: Any = _MISSING,
        lower: float = -math.inf,
        upper: float = math.inf,
        unit: str = "",
    ) -> float:
        if key not in mapping:
            if default is _MISSING:
                raise self.error(mapping.line, _join(field, key), "required but missing")
            return float(default)
        value = mapping[key]
        where = (mapping.line_of(key), _join(field, key))
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(*where, f"expected a number{_in(unit)}, got {_kind(value)}")
        if not math.isfinite(value) or not lower <= value <= upper:
            raise self.error(
                *where, f"{_shown(value)} is outside [{lower:g}, {upper:g}]{_in(unit)}"
            )
        return float(value)

    def boolean(self, mapping: LocatedDict, key: str, field: str, default: bool) -> bool:
        value = mapping.get(key, default)
        if not isinstance(value, bool):
            raise self.error(
                mapping.line_of(key),
                _join(field, key),
                f"expected true or false, got {_kind(value)}",
            )
        return value

    def text(self, mapping: LocatedDict, key: str, field: str, default: Any = _MISSING) -> str:
        if key not in mapping:
            if default is _MISSING:
                raise self.error(mapping.line, _join(field, key), "required but missing")
            return str(default)
        value = mapping[key]
        if not isinstance(value, str):
            raise self.error(
                mapping.line_of(key), _join(field, key), f"expected text, got {_kind(value)}"
            )
        if len(value) > MAX_TEXT_CHARS:
            raise self.error(
                mapping.line_of(key),
                _join(field, key),
                f"{_shown(value)} is longer than {MAX_TEXT_CHARS} characters",
            )
        return value

    def numbers(
        self, mapping: LocatedDict, key: str, field: str, lengths: Sequence[int], unit: str = ""
    ) -> tuple[float, ...]:
        value = mapping[key]
        where = (mapping.line_of(key), _join(field, key))
        if not isinstance(value, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        ):
            raise self.error(*where, f"expected a list of finite numbers{_in(unit)}")
        if len(value) not in lengths:
            expected = " or ".join(str(n) for n in lengths)
            raise self.error(*where, f"expected {expected} numbers{_in(unit)}, got {len(value)}")
        return tuple(float(v) for v in value)


def _join(field: str, key: str) -> str:
    return f"{field}.{key}" if field else key


def _in(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def _kind(value: Any) -> str:
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    return _shown(value)


def _shown(value: Any) -> str:
    """``repr(value)``, cut short (a spec may hold a megabyte of text in one value)."""
    text = repr(value)
    if len(text) <= SHOWN_CHARS:
        return text
    return f"{text[: SHOWN_CHARS - 16]}... ({len(text)} characters)"
