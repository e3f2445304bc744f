"""Controller parameters: a schema per controller type, files in ``controllers/``.

Like ros2_controllers' parameter files: each parameter has a type, a default,
bounds and a description; a file gives values for one controller, and one arm
may override any of them without touching another arm's.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from armfleet.errors import ParameterError
from armfleet.paths import data_dir


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter of a controller type.

    Attributes:
        name: key in the file, with its unit as a suffix where it has one.
        default: value when the file does not give one.
        description: what it does, with units.
        lower, upper: inclusive bounds.
    """

    name: str
    default: float
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
) -> dict[str, float]:
    """Read ``path`` (default: the controller's shipped file), apply ``overrides``, validate.

    The file holds ``{<controller>: {<parameter>: value, ...}}``.

    Raises:
        ParameterError: unknown key (with a "did you mean"), wrong type or out of bounds.
    """
    path = path or controller_file(controller)
    try:
        document = yaml.safe_load(path.read_text()) if path.is_file() else {}
    except yaml.YAMLError as exc:
        raise ParameterError(f"{path}: not valid YAML: {exc}") from None
    section = (document or {}).get(controller, {}) if isinstance(document, dict) else None
    if not isinstance(section, dict):
        raise ParameterError(f"{path}: expected a mapping under '{controller}:'")
    values = {spec.name: spec.default for spec in schema}
    for source, given in ((str(path), section), ("override", overrides or {})):
        for key, value in given.items():
            values[key] = _check(controller, source, schema, key, value)
    return values


def _check(
    controller: str, source: str, schema: Sequence[ParameterSpec], key: str, value: Any
) -> float:
    specs = {spec.name: spec for spec in schema}
    spec = specs.get(key)
    if spec is None:
        close = difflib.get_close_matches(key, specs, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        raise ParameterError(
            f"{source}: unknown {controller} parameter '{key}'; {hint}"
            f"valid: {', '.join(sorted(specs))}"
        )
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ParameterError(f"{source}: {controller}.{key} = {value!r} must be a finite number")
    if not spec.lower <= value <= spec.upper:
        raise ParameterError(
            f"{source}: {controller}.{key} = {value} is outside [{spec.lower:g}, {spec.upper:g}]"
        )
    return float(value)
