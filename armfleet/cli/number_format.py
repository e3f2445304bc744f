"""Numbers as the CLI prints them: fixed decimals, and never a negative zero."""

from __future__ import annotations


def fixed(value: float, digits: int, sign: str = "") -> str:
    """``value`` with ``digits`` decimals (``sign="+"``: always signed), never ``-0.000``.

    A value that rounds to zero prints as zero: a joint resting at -1e-7 rad, a closed
    gripper at -1e-6 m, a yaw of -0.4 deg printed to the degree.
    """
    rounded = round(float(value), digits) + 0.0  # -0.0 + 0.0 is 0.0
    return f"{rounded:{sign}.{digits}f}"
