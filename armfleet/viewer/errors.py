"""Errors of the viewer."""

from __future__ import annotations

from armfleet.errors import ArmfleetError


class ViewerError(ArmfleetError):
    """The viewer cannot do what was asked (its server did not start, died or hangs)."""


class ViewerTimeout(ViewerError):
    def __init__(self, request: str, timeout_s: float) -> None:
        self.request = request
        self.timeout_s = timeout_s
        super().__init__(f"the viewer server did not answer {request!r} within {timeout_s:g} s")
