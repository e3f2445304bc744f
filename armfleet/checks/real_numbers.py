"""The one rule for what counts as a number a user gave: a real, finite int or float.

Python's ``float()`` and NumPy's ``asarray(..., dtype=float)`` accept more than a
user means: ``float("0.04")`` reads text, ``float(True)`` is 1.0, NumPy drops an
imaginary part or parses strings, and ``float(None)`` escapes as a ``TypeError``.
Every public entry point that takes a number or a vector of numbers (world
settings, durations, joint targets, spawn poses, poses, gripper widths and
forces, object sizes) goes through :func:`is_real` / :func:`all_real`, so all
refuse the same things: text, bytes, bool, complex, None, and anything else that
is not a real number.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np

from armfleet.errors import InvalidNumber
from armfleet.messages import FloatArray

#: NumPy dtype kinds of real numbers: signed and unsigned integers, floats (not bool).
_REAL_KINDS = "iuf"

#: What a message stamp must be (``arm.status(stamp)``, ``gripper.state(stamp)``).
STAMP_VALID = "a time >= 0 s (e.g. world.time)"


def is_real(value: object) -> bool:
    """Whether ``value`` is one real number: an int, a float, a NumPy integer or
    floating scalar (or 0-d array); not a bool, text, complex or None."""
    if isinstance(value, np.ndarray):
        return value.ndim == 0 and value.dtype.kind in _REAL_KINDS
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


def all_real(values: object) -> bool:
    """Whether ``values`` is a (possibly nested) sequence or array (or array-like: anything
    with ``__array__``) whose every element :func:`is_real`; a bare number counts too.
    Mappings, sets, text and iterators don't."""
    if not isinstance(values, np.ndarray) and hasattr(values, "__array__"):
        try:  # an array-like (pin.SE3, a tensor, a pandas Series)
            values = np.asarray(values)
        except (TypeError, ValueError):
            return False
    if isinstance(values, np.ndarray):
        if values.dtype.kind == "O":
            return all(is_real(v) for v in values.flat)
        return values.dtype.kind in _REAL_KINDS
    if isinstance(values, Sequence) and not isinstance(values, str | bytes):
        return all(all_real(v) for v in values)
    return is_real(values)


def is_real_vector(values: object) -> bool:
    """Whether ``values`` is a flat sequence (or 1-D array) of :func:`is_real` numbers."""
    if isinstance(values, np.ndarray):
        return values.ndim == 1 and all_real(values)
    return (
        isinstance(values, Sequence)
        and not isinstance(values, str | bytes)
        and all(is_real(v) for v in values)
    )


def real_number(
    value: object,
    argument: str,
    valid: str,
    *,
    low: float = -math.inf,
    high: float = math.inf,
    finite: bool = True,
) -> float:
    """``value`` as a float if it is a finite real number in ``[low, high]``.

    Args:
        value: what the user gave.
        argument: its name in the message (``"dt"``, ``"bob: gripper width"``).
        valid: what would be right, with its unit (``"a step in [1e-05, 0.002] s"``).
        low, high: inclusive bounds.
        finite: check finiteness and bounds; with False only the type is checked,
            for callers that name a value out of range in their own error.

    Raises:
        InvalidNumber: naming ``argument``, the value and ``valid``.
    """
    if not is_real(value):
        raise InvalidNumber(argument, value, valid)
    number = float(value)  # type: ignore[arg-type]  # is_real checked it
    if finite and not (math.isfinite(number) and low <= number <= high):
        raise InvalidNumber(argument, number, valid)
    return number


def real_array(values: object, argument: str, valid: str) -> FloatArray:
    """``values`` (a sequence or array of real numbers, any shape) as a float array.

    Non-finite elements pass (callers name the element); the shape is the caller's.

    Raises:
        InvalidNumber: not numbers (text, bool, complex, None, a mapping, ragged rows).
    """
    if not all_real(values):
        raise InvalidNumber(argument, values, valid)
    try:
        return np.asarray(values, dtype=float)
    except ValueError:  # ragged nested sequences
        raise InvalidNumber(argument, values, valid) from None
