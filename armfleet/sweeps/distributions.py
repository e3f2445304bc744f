"""The distributions a sweep draws its parameters from, written in the spec's units.

In YAML, one key names the kind and holds its numbers; each number may be a list,
for a vector parameter (drawn element by element)::

    {uniform: [low, high]}                 # low <= x < high
    {normal: [mean, std], clip: [lo, hi]}  # clip: required where the value is bounded
    {integers: [low, high]}                # a whole number, both ends included
    {choice: [a, b, c]}                    # one of the values, equally likely

A distribution knows its support (the smallest and largest value it can give), so a
sweep can refuse one that reaches outside its parameter's range before any run starts.
It is also refused when it is written where NumPy's generator cannot draw from it, so
that no worker meets the problem: a uniform whose ``high - low`` overflows, a normal
whose draws could overflow to infinity, integer bounds outside int64.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armfleet.checks.real_numbers import is_real

#: Names of the kinds, for messages.
KINDS = ("uniform", "normal", "integers", "choice")

Value = float | int | tuple[float, ...]

#: The bounds of ``integers`` (NumPy's generator draws int64).
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
#: Largest magnitude a whole number keeps exactly as a float (a choice of larger whole
#: numbers gives floats).
EXACT_FLOAT_INTEGER = 2**53
#: Standard deviations a normal's draw may reach before it would overflow to infinity.
NORMAL_REACH_STD = 40.0


class DistributionError(ValueError):
    """A distribution written wrongly; the message names the problem."""


class Distribution(ABC):
    """Where one parameter's value comes from.

    Attributes:
        size: elements of the value: 0 for a scalar, n for a vector of n numbers.
    """

    size: int

    @abstractmethod
    def draw(self, rng: np.random.Generator) -> Value:
        """One value: a float or int for a scalar, a tuple of floats for a vector."""

    @abstractmethod
    def support(self) -> tuple[np.ndarray, np.ndarray]:
        """The smallest and largest value of each element (arrays of ``max(size, 1)``)."""

    @property
    def is_integer(self) -> bool:
        """Whether it gives whole numbers only."""
        return False


@dataclass(frozen=True)
class Uniform(Distribution):
    low: np.ndarray
    high: np.ndarray
    size: int

    def draw(self, rng: np.random.Generator) -> Value:
        return _shaped(rng.uniform(self.low, self.high), self.size)

    def support(self) -> tuple[np.ndarray, np.ndarray]:
        return self.low, self.high


@dataclass(frozen=True)
class Normal(Distribution):
    mean: np.ndarray
    std: np.ndarray
    size: int
    clip: tuple[np.ndarray, np.ndarray] | None = None

    def draw(self, rng: np.random.Generator) -> Value:
        value = rng.normal(self.mean, self.std)
        if self.clip is not None:
            value = np.clip(value, *self.clip)
        return _shaped(value, self.size)

    def support(self) -> tuple[np.ndarray, np.ndarray]:
        if self.clip is not None:
            return self.clip
        unbounded = np.full_like(self.mean, math.inf)
        return np.where(self.std > 0, -unbounded, self.mean), np.where(
            self.std > 0, unbounded, self.mean
        )


@dataclass(frozen=True)
class Integers(Distribution):
    """Whole numbers from ``low`` to ``high``, both included.

    Attributes:
        low, high: the bounds, as floats (for the support and the sweep's fingerprint).
        exact_low, exact_high: the same bounds exactly, as int64 (what is drawn from).
    """

    low: np.ndarray
    high: np.ndarray
    size: int
    exact_low: np.ndarray = field(repr=False, compare=False)
    exact_high: np.ndarray = field(repr=False, compare=False)

    def draw(self, rng: np.random.Generator) -> Value:
        value = rng.integers(self.exact_low, self.exact_high, endpoint=True)
        if self.size == 0:
            return int(value[0])
        return tuple(float(v) for v in value)

    def support(self) -> tuple[np.ndarray, np.ndarray]:
        return self.low, self.high

    @property
    def is_integer(self) -> bool:
        return True


@dataclass(frozen=True)
class Choice(Distribution):
    values: np.ndarray  # rows: the choices
    size: int

    def draw(self, rng: np.random.Generator) -> Value:
        row = self.values[int(rng.integers(len(self.values)))]
        if self.size == 0 and self.is_integer:
            return int(row[0])
        return _shaped(row if self.size else row[0], self.size)

    def support(self) -> tuple[np.ndarray, np.ndarray]:
        return self.values.min(axis=0), self.values.max(axis=0)

    @property
    def is_integer(self) -> bool:
        """Whole numbers that a float holds exactly (larger ones are drawn as floats)."""
        return bool(
            np.all(self.values == np.round(self.values))
            and np.all(np.abs(self.values) <= EXACT_FLOAT_INTEGER)
        )


def parse_distribution(entry: object) -> tuple[Distribution, bool]:
    """A distribution from its YAML mapping, and whether it is ``relative`` (added to the
    spec's value rather than replacing it).

    Raises:
        DistributionError: an unknown kind, numbers of different lengths, ``low > high``,
            a negative standard deviation, a non-finite number, an empty choice, or
            numbers NumPy's generator cannot draw from (integer bounds outside int64, a
            uniform whose ``high - low`` overflows, a normal that could draw infinity).
    """
    if not isinstance(entry, Mapping):
        raise DistributionError(
            f"a distribution is a mapping such as {{uniform: [low, high]}}; kinds: "
            f"{', '.join(KINDS)}"
        )
    kinds = [key for key in entry if key in KINDS]
    extra = [str(key) for key in entry if key not in (*KINDS, "clip", "relative")]
    if extra:
        raise DistributionError(
            f"unknown key {extra[0]!r} in a distribution; valid: {', '.join(KINDS)}, "
            "clip (normal only), relative"
        )
    if len(kinds) != 1:
        raise DistributionError(
            f"give exactly one of {', '.join(KINDS)} (got {', '.join(kinds) or 'none'})"
        )
    relative = entry.get("relative", False)
    if not isinstance(relative, bool):
        raise DistributionError(f"relative is true or false, got {relative!r}")
    kind = kinds[0]
    if "clip" in entry and kind != "normal":
        raise DistributionError(f"clip applies to normal only, not to {kind}")
    numbers = entry[kind]
    if kind == "choice":
        return _choice(numbers), relative
    low, high, size = _pair(kind, numbers)
    if kind == "normal":
        if np.any(high < 0):
            raise DistributionError("normal: the standard deviation must be >= 0")
        with np.errstate(over="ignore"):
            reach = np.abs(low) + NORMAL_REACH_STD * high
        if not np.all(np.isfinite(reach)):
            raise DistributionError(
                f"normal: mean {low.tolist()} and std {high.tolist()} are so large that a "
                f"draw could overflow to infinity (|mean| + {NORMAL_REACH_STD:g} std must "
                "stay below 1.8e308)"
            )
        clip = None
        if "clip" in entry:
            clip_low, clip_high, clip_size = _pair("clip", entry["clip"])
            if clip_size not in (0, size):
                raise DistributionError("clip: give as many numbers as the mean")
            _ordered("clip", clip_low, clip_high)
            clip = (clip_low * np.ones_like(low), clip_high * np.ones_like(low))
        return Normal(low, high, size, clip), relative
    _ordered(kind, low, high)
    if kind == "integers":
        exact_low, exact_high = (_int64_bounds(part) for part in numbers)
        if np.any(exact_low > exact_high):
            raise DistributionError(
                f"integers: low {exact_low.tolist()} is above high {exact_high.tolist()}"
            )
        return Integers(low, high, size, exact_low, exact_high), relative
    with np.errstate(over="ignore"):
        width = high - low
    if not np.all(np.isfinite(width)):
        raise DistributionError(
            f"uniform: high - low overflows ({low.tolist()} to {high.tolist()}); NumPy draws "
            "a uniform only where high - low is below 1.8e308"
        )
    return Uniform(low, high, size), relative


def _pair(kind: str, numbers: object) -> tuple[np.ndarray, np.ndarray, int]:
    """Two scalars or two equal-length vectors, as arrays, and the size (0: scalar)."""
    if not isinstance(numbers, Sequence) or isinstance(numbers, str) or len(numbers) != 2:
        what = "[mean, std]" if kind == "normal" else "[low, high]"
        raise DistributionError(f"{kind}: give {what}, each a number or a list of numbers")
    first, second = (_vector(kind, part) for part in numbers)
    if len(first[0]) != len(second[0]) or first[1] != second[1]:
        raise DistributionError(f"{kind}: both ends need as many numbers")
    return first[0], second[0], first[1]


def _vector(kind: str, part: object) -> tuple[np.ndarray, int]:
    if _finite(part):
        return np.array([float(part)]), 0  # type: ignore[arg-type]
    if (
        isinstance(part, Sequence)
        and not isinstance(part, str)
        and 0 < len(part) <= 64
        and all(_finite(x) for x in part)
    ):
        return np.array([float(x) for x in part]), len(part)
    raise DistributionError(f"{kind}: {_short(part)} is not a finite number or list of numbers")


def _finite(value: object) -> bool:
    """Whether ``value`` is one real number a float holds finitely (a huge int is not)."""
    if not is_real(value):
        return False
    try:
        return math.isfinite(float(value))  # type: ignore[arg-type]
    except OverflowError:
        return False


def _int64_bounds(part: object) -> np.ndarray:
    """One end of ``integers`` as exact int64s (the numbers as written, not as floats).

    Raises:
        DistributionError: a number that is not whole or lies outside int64.
    """
    given: list[Any] = list(part) if isinstance(part, Sequence) else [part]  # real numbers
    exact = []
    for number in given:
        if not isinstance(number, int | np.integer) and not float(number).is_integer():
            raise DistributionError(
                f"integers: {_short(number)} is not a whole number; give whole numbers"
            )
        whole = int(number)
        if not INT64_MIN <= whole <= INT64_MAX:
            raise DistributionError(
                f"integers: {_short(number)} is outside what can be drawn, the int64 range "
                f"[{INT64_MIN}, {INT64_MAX}]"
            )
        exact.append(whole)
    return np.array(exact, dtype=np.int64)


def _short(value: object) -> str:
    """``repr(value)``, cut to a length a one-line message can hold."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _ordered(kind: str, low: np.ndarray, high: np.ndarray) -> None:
    if np.any(low > high):
        raise DistributionError(f"{kind}: low {low.tolist()} is above high {high.tolist()}")


def _choice(values: object) -> Choice:
    if not isinstance(values, Sequence) or isinstance(values, str) or not values:
        raise DistributionError("choice: give a non-empty list of values")
    rows = [_vector("choice", value) for value in values]
    sizes = {size for _, size in rows}
    lengths = {len(row) for row, _ in rows}
    if len(sizes) != 1 or len(lengths) != 1:
        raise DistributionError("choice: every value needs as many numbers")
    return Choice(np.array([row for row, _ in rows]), sizes.pop())


def _shaped(value: np.ndarray, size: int) -> Value:
    array = np.asarray(value, dtype=float)
    if size == 0:
        return float(array.reshape(-1)[0])
    return tuple(float(v) for v in array)
