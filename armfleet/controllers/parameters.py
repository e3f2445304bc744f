"""Controller parameters: a schema per controller type, files in ``controllers/``.

Like ros2_controllers' parameter files: each parameter has a type, a default,
bounds and a description; a file gives values for one controller, and one arm
may override any of them without touching another arm's.
"""

from __future__ import annotations

import difflib
import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from armfleet.checks.located_yaml import LocatedDict, YamlDocumentError, read_located
from armfleet.checks.user_paths import file_problem
from armfleet.description.data_folders import data_dir
from armfleet.errors import ParameterError


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter of a controller type.

    Attributes:
        name: key in the file, with its unit as a suffix where it has one.
        default: value when the file does not give one; a bool default makes
            the parameter a switch (true/false).
        description: what it does, with units.
        lower, upper: inclusive bounds.
    """

    name: str
    default: float | bool
    description: str
    lower: float = -math.inf
    upper: float = math.inf


def controller_file(controller: str) -> Path:
    """``controllers/<controller>.yaml`` of this armfleet."""
    return data_dir("controllers") / f"{controller}.yaml"


def load_parameters(
    controller: str,
    schema: Sequence[ParameterSpec],
    path: Path | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> dict[str, float | bool]:
    """Read ``path`` (default: the controller's shipped file), apply ``overrides``, validate.

    The file holds ``{<controller>: {<parameter>: value, ...}}``.

    Raises:
        ParameterError: unknown key (with a "did you mean"), wrong type or out of bounds.
    """
    path = path or controller_file(controller)
    problem = file_problem(path)  # a folder, device or pipe is no file to read either
    if problem is not None:
        raise ParameterError(
            f"{path}: controller parameter file {problem}; give a YAML file "
            f"like {controller_file(controller)}"
        )
    stat = path.stat()
    document = _parsed(path, stat.st_mtime_ns, stat.st_size)
    if not isinstance(document, LocatedDict) or controller not in document:
        found = ", ".join(document) if isinstance(document, LocatedDict) else "nothing"
        raise ParameterError(f"{path}: no '{controller}:' section (found: {found})")
    section = document[controller]
    if not isinstance(section, LocatedDict):
        line = document.line_of(controller)
        raise ParameterError(
            f"{path}:{line}: expected parameters as a mapping under '{controller}:'"
        )
    values = {spec.name: spec.default for spec in schema}
    for key, value in section.items():
        values[key] = _check(controller, f"{path}:{section.line_of(key)}", schema, key, value)
    for key, value in (overrides or {}).items():
        values[key] = _check(controller, "override", schema, key, value)
    return values


@functools.lru_cache(maxsize=64)
def _parsed(path: Path, mtime_ns: int, size: int) -> Any:
    """The located YAML of ``path``, parsed once per version of the file (every arm of a
    fleet reads the same few files; the result is only read, never changed)."""
    del mtime_ns, size  # part of the cache key only
    try:
        return read_located(path)
    except YamlDocumentError as exc:
        raise ParameterError(str(exc)) from None


def _check(
    controller: str, source: str, schema: Sequence[ParameterSpec], key: str, value: Any
) -> float | bool:
    try:
        return check_parameter(controller, schema, key, value)
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None


def check_parameter(
    controller: str, schema: Sequence[ParameterSpec], key: str, value: Any
) -> float | bool:
    """Return ``value`` as a float if ``key`` is a parameter of ``schema`` and fits it."""
    specs = {spec.name: spec for spec in schema}
    spec = specs.get(key)
    if spec is None:
        close = difflib.get_close_matches(key, specs, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        raise ParameterError(
            f"unknown {controller} parameter '{key}'; {hint}valid: {', '.join(sorted(specs))}"
        )
    if isinstance(spec.default, bool):
        if not isinstance(value, bool):
            raise ParameterError(f"{controller}.{key} = {value!r} must be true or false")
        return value
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ParameterError(f"{controller}.{key} = {value!r} must be a finite number")
    if not spec.lower <= value <= spec.upper:
        raise ParameterError(
            f"{controller}.{key} = {value} is outside [{spec.lower:g}, {spec.upper:g}]"
        )
    return float(value)  # a switch is returned as a bool above
