"""What a sweep draws per run, and how a draw changes the launch spec or the task.

A randomization is a list of :class:`RandomParameter`: a target and a distribution.
Targets, each in the spec's units:

=====================================================  ============================
``arms.<arm>.at_m``                                    base x, y[, z] [m]
``arms.<arm>.yaw_deg``                                 base yaw [deg]
``arms.<arm>.controllers.<controller>.<parameter>``    a controller parameter
``objects.<object>.at_m`` / ``rpy_deg`` / ``yaw_deg``  object pose [m, deg]
``objects.<object>.size_m`` / ``mass_kg`` / ``friction``
``world.gravity_m_s2``                                 [m/s^2]
``task.<keyword>``                                     a keyword argument of the task
=====================================================  ============================

With ``relative: true`` the drawn value is added to the spec's value (an offset);
its column is then named ``<target>.offset``. Each parameter draws from its own stream,
seeded by the run's seed and the target's name, so adding a parameter to a sweep does
not change what the others draw.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from armfleet.controllers.parameters import load_parameters
from armfleet.controllers.registry import CONTROLLER_TYPES
from armfleet.objects.object_spec import ObjectSpec
from armfleet.spec import ArmSpec, ControllerConfig, FleetSpec
from armfleet.sweeps.distributions import Distribution, Value

ARM_FIELDS = ("at_m", "yaw_deg", "controllers")
OBJECT_FIELDS = ("at_m", "rpy_deg", "yaw_deg", "size_m", "mass_kg", "friction")
ROOTS = ("arms", "objects", "world", "task")


class TargetError(ValueError):
    """A target that does not exist or a distribution that does not fit it."""


@dataclass(frozen=True)
class RandomParameter:
    """One randomized number (or vector) of a sweep.

    Attributes:
        target: what it sets, e.g. ``objects.bar.at_m``.
        distribution: where its value comes from.
        relative: the value is added to the spec's value.
    """

    target: str
    distribution: Distribution
    relative: bool = False

    @property
    def column(self) -> str:
        """Its column in the results (a vector's elements are ``column[i]``)."""
        return f"{self.target}.offset" if self.relative else self.target

    @property
    def columns(self) -> tuple[str, ...]:
        size = self.distribution.size
        return (self.column,) if size == 0 else tuple(f"{self.column}[{i}]" for i in range(size))

    def draw(self, seed: int) -> Value:
        """Its value in the run of ``seed``."""
        stream = np.random.default_rng([seed, zlib.crc32(self.target.encode())])
        return self.distribution.draw(stream)

    def row(self, value: Value) -> dict[str, float | int]:
        """``value`` under :attr:`columns`."""
        if isinstance(value, tuple):
            return dict(zip(self.columns, value, strict=True))
        return {self.column: value}


def check_target(parameter: RandomParameter, spec: FleetSpec, task_keywords: set[str]) -> None:
    """Refuse a target that ``spec`` or the task does not have, or a distribution whose
    values could fall outside what the target accepts.

    Args:
        task_keywords: the task's keyword parameters; empty set plus ``"**"`` for a task
            that takes any keyword.

    Raises:
        TargetError: naming the problem and the valid choices.
    """
    parts = parameter.target.split(".")
    low, high = parameter.distribution.support()
    size = parameter.distribution.size
    if parts[0] not in ROOTS or len(parts) < 2:
        raise TargetError(f"unknown target; targets start with {', '.join(ROOTS)}")
    if parts[0] == "task":
        if len(parts) != 2 or not parts[1].isidentifier():
            raise TargetError("a task parameter is task.<keyword>")
        if parts[1] not in task_keywords and "**" not in task_keywords:
            valid = ", ".join(sorted(task_keywords - {"**"})) or "none"
            raise TargetError(f"the task takes no keyword {parts[1]!r}; its keywords: {valid}")
        if parameter.relative:
            raise TargetError("a task parameter has no spec value to be relative to")
        return
    if parts[0] == "world":
        if parts[1:] != ["gravity_m_s2"]:
            raise TargetError("the world's randomizable number is world.gravity_m_s2")
        _check_range(parameter, spec.world.gravity_m_s2, size, (), low, high, -100.0, 100.0)
        return
    if len(parts) < 3:
        raise TargetError(f"give {parts[0]}.<name>.<field>")
    if parts[0] == "arms":
        _check_arm(parameter, spec, parts, low, high)
    else:
        _check_object(parameter, spec, parts, low, high)


def _check_arm(
    parameter: RandomParameter,
    spec: FleetSpec,
    parts: list[str],
    low: np.ndarray,
    high: np.ndarray,
) -> None:
    arm = _arm(spec, parts[1])
    field, size = parts[2], parameter.distribution.size
    if field not in ARM_FIELDS:
        raise TargetError(f"unknown arm field {field!r}; valid: {', '.join(ARM_FIELDS)}")
    if field == "at_m":
        base = (arm.pose.x, arm.pose.y, arm.pose.z)[: max(size, 2)]
        _check_parts(parameter, len(parts), 3)
        _check_range(parameter, base, size, (2, 3), low, high, -1e4, 1e4)
    elif field == "yaw_deg":
        _check_parts(parameter, len(parts), 3)
        _check_range(parameter, arm.pose.yaw_deg, size, (0,), low, high, -360.0, 360.0)
    else:
        _check_parts(parameter, len(parts), 5)
        controller, name = parts[3], parts[4]
        if controller not in CONTROLLER_TYPES:
            raise TargetError(
                f"unknown controller {controller!r}; valid: {', '.join(CONTROLLER_TYPES)}"
            )
        schema = {spec.name: spec for spec in CONTROLLER_TYPES[controller].parameter_schema}
        if name not in schema or isinstance(schema[name].default, bool):
            numbers = sorted(n for n, s in schema.items() if not isinstance(s.default, bool))
            raise TargetError(
                f"{controller} has no numeric parameter {name!r}; valid: {', '.join(numbers)}"
            )
        value = _controller_value(arm, controller, name)
        lower, upper = schema[name].lower, schema[name].upper
        _check_range(parameter, value, size, (0,), low, high, lower, upper)


def _check_object(
    parameter: RandomParameter,
    spec: FleetSpec,
    parts: list[str],
    low: np.ndarray,
    high: np.ndarray,
) -> None:
    obj = _object(spec, parts[1])
    field, size = parts[2], parameter.distribution.size
    _check_parts(parameter, len(parts), 3)
    if field == "at_m":
        _check_range(parameter, obj.at[: max(size, 2)], size, (2, 3), low, high, -1e4, 1e4)
    elif field == "rpy_deg":
        _check_range(parameter, obj.rpy_deg, size, (3,), low, high, -360.0, 360.0)
    elif field == "yaw_deg":
        _check_range(parameter, obj.rpy_deg[2], size, (0,), low, high, -360.0, 360.0)
    elif field == "size_m":
        _check_range(parameter, obj.size, size, (len(obj.size),), low, high, 1e-4, 100.0)
    elif field == "mass_kg":
        _check_range(parameter, obj.mass_kg, size, (0,), low, high, 0.0, 1e4)
    elif field == "friction":
        _check_range(parameter, obj.friction, size, (0,), low, high, 0.0, 100.0)
    else:
        raise TargetError(f"unknown object field {field!r}; valid: {', '.join(OBJECT_FIELDS)}")


def _check_parts(parameter: RandomParameter, parts: int, expected: int) -> None:
    if parts != expected:
        raise TargetError(f"unknown target {parameter.target!r}")


def _check_range(
    parameter: RandomParameter,
    base: float | tuple[float, ...],
    size: int,
    sizes: tuple[int, ...],
    low: np.ndarray,
    high: np.ndarray,
    lower: float,
    upper: float,
) -> None:
    """Refuse a wrong vector length, or values outside ``[lower, upper]``."""
    if sizes and size not in sizes:
        shown = " or ".join("a number" if s == 0 else str(s) for s in sizes)
        shown += "" if sizes == (0,) else " numbers"
        raise TargetError(f"give {shown}")
    offset = (
        np.atleast_1d(np.asarray(base, dtype=float))[: max(size, 1)] if parameter.relative else 0.0
    )
    smallest, largest = low + offset, high + offset
    if np.any(smallest < lower) or np.any(largest > upper):
        what = "with the spec's value added, " if parameter.relative else ""
        raise TargetError(
            f"its values, {what}reach [{_shown(smallest)}, {_shown(largest)}], outside the "
            f"valid range [{_shown(lower)}, {_shown(upper)}]"
            + ("; add clip: [low, high] to a normal" if not np.all(np.isfinite(low)) else "")
        )


def _shown(value: Any) -> str:
    array = np.atleast_1d(np.asarray(value, dtype=float))
    texts = [f"{v:g}" for v in array]
    return texts[0] if len(texts) == 1 else "(" + ", ".join(texts) + ")"


def _arm(spec: FleetSpec, name: str) -> ArmSpec:
    for arm in spec.arms:
        if arm.name == name:
            return arm
    names = ", ".join(arm.name for arm in spec.arms) or "none"
    raise TargetError(f"the spec has no arm {name!r}; its arms: {names}")


def _object(spec: FleetSpec, name: str) -> ObjectSpec:
    for obj in spec.objects:
        if obj.name == name:
            return obj
    names = ", ".join(obj.name for obj in spec.objects) or "none"
    raise TargetError(f"the spec has no object {name!r}; its objects: {names}")


def _controller_value(arm: ArmSpec, controller: str, name: str) -> float:
    config = arm.controllers.get(controller, ControllerConfig())
    schema = CONTROLLER_TYPES[controller].parameter_schema
    values = load_parameters(controller, schema, config.file, config.parameters)
    return float(values[name])


def apply_draws(
    spec: FleetSpec, draws: Sequence[tuple[RandomParameter, Value]]
) -> tuple[FleetSpec, dict[str, Value]]:
    """The spec of one run, and the task's drawn keywords.

    Each parameter must have passed :func:`check_target` against ``spec``.
    """
    keywords: dict[str, Value] = {}
    arms = {arm.name: arm for arm in spec.arms}
    objects = {obj.name: obj for obj in spec.objects}
    world = spec.world
    for parameter, value in draws:
        parts = parameter.target.split(".")
        if parts[0] == "task":
            keywords[parts[1]] = value
        elif parts[0] == "world":
            world = replace(world, gravity_m_s2=_set(world.gravity_m_s2, value, parameter))
        elif parts[0] == "arms":
            arms[parts[1]] = _arm_with(arms[parts[1]], parts, value, parameter)
        else:
            objects[parts[1]] = _object_with(objects[parts[1]], parts[2], value, parameter)
    changed = replace(
        spec,
        world=world,
        arms=tuple(arms[arm.name] for arm in spec.arms),
        objects=tuple(objects[obj.name] for obj in spec.objects),
    )
    return changed, keywords


def _set(base: Any, value: Value, parameter: RandomParameter) -> Any:
    """``value``, or ``base + value`` for a relative parameter, as the base's type."""
    if isinstance(value, tuple):
        start = tuple(float(b) for b in base)
        drawn = tuple(float(v) for v in value)
        if parameter.relative:
            drawn = tuple(b + v for b, v in zip(start, drawn, strict=False))
        return drawn + start[len(drawn) :]
    return float(base) + float(value) if parameter.relative else float(value)


def _arm_with(arm: ArmSpec, parts: list[str], value: Value, parameter: RandomParameter) -> ArmSpec:
    pose = arm.pose
    if parts[2] == "at_m":
        x, y, z = _set((pose.x, pose.y, pose.z), value, parameter)
        return replace(arm, pose=replace(pose, x=x, y=y, z=z))
    if parts[2] == "yaw_deg":
        return replace(arm, pose=replace(pose, yaw_deg=_set(pose.yaw_deg, value, parameter)))
    controller, name = parts[3], parts[4]
    config = arm.controllers.get(controller, ControllerConfig())
    number = _set(_controller_value(arm, controller, name), value, parameter)
    controllers = dict(arm.controllers)
    controllers[controller] = ControllerConfig(config.file, {**config.parameters, name: number})
    return replace(arm, controllers=controllers)


def _object_with(
    obj: ObjectSpec, field: str, value: Value, parameter: RandomParameter
) -> ObjectSpec:
    if field == "at_m":
        return replace(obj, at=_set(obj.at, value, parameter))
    if field == "rpy_deg":
        return replace(obj, rpy_deg=_set(obj.rpy_deg, value, parameter))
    if field == "yaw_deg":
        roll, pitch, yaw = obj.rpy_deg
        return replace(obj, rpy_deg=(roll, pitch, _set(yaw, value, parameter)))
    if field == "size_m":
        return replace(obj, size=_set(obj.size, value, parameter))
    if field == "mass_kg":
        return replace(obj, mass_kg=_set(obj.mass_kg, value, parameter))
    return replace(obj, friction=_set(obj.friction, value, parameter))
