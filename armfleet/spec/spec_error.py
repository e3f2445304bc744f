"""The error of a launch spec: file, line, field, problem and the valid choices."""

from __future__ import annotations

from armfleet.errors import ArmfleetError


class SpecError(ArmfleetError):
    """A launch spec that cannot be used.

    Attributes:
        source: the spec file (or ``"command line"``).
        line: 1-based line of the offending field (0 if unknown).
        field: dotted path of the field, e.g. ``arms[1].model``.
        problem: what is wrong and what would be right.
    """

    def __init__(self, source: str, line: int, field: str, problem: str) -> None:
        self.source, self.line, self.field, self.problem = source, line, field, problem
        where = f"{source}:{line}" if line else source
        super().__init__(f"{where}: {field}: {problem}" if field else f"{where}: {problem}")
