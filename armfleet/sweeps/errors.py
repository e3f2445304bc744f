"""The error of a sweep that cannot start: one line naming the problem and the choices."""

from __future__ import annotations

from armfleet.errors import ArmfleetError


class SweepError(ArmfleetError):
    """A sweep refused before any run starts (an unknown scenario, a task that is not
    callable, a distribution outside its parameter's range, ``runs`` of 0, an address
    that cannot be reached), or a results file that cannot be read or resumed."""
