"""Errors of the learning environments: each names what is wrong and what is valid."""

from __future__ import annotations

from collections.abc import Iterable

from armfleet.errors import ArmfleetError


class EnvError(ArmfleetError):
    """Root of the environments' errors."""


class InvalidAction(EnvError):
    """An action the environment refuses; nothing was applied and no time passed.

    Attributes:
        arm: the arm whose action is wrong ("" for the action as a whole).
        field: the entry of the arm's action (``"joints"``, ``"gripper"``) or ``""``.
        problem: what is wrong with it.
        valid: what would be accepted.
    """

    def __init__(self, arm: str, field: str, problem: str, valid: str) -> None:
        self.arm, self.field, self.problem, self.valid = arm, field, problem, valid
        where = "action" + (f"[{arm!r}]" if arm else "") + (f"[{field!r}]" if field else "")
        super().__init__(f"{where}: {problem}; valid: {valid}")


class InvalidOption(EnvError):
    """A construction option with a value the environment does not take.

    Attributes:
        option: its name.
        value: what was given.
        choices: the values or the range it takes.
    """

    def __init__(self, option: str, value: object, choices: Iterable[str] | str) -> None:
        self.option, self.value = option, value
        self.choices = choices if isinstance(choices, str) else ", ".join(choices)
        shown = " ".join(repr(value).split())
        if len(shown) > 60:
            shown = shown[:57] + "..."
        super().__init__(f"{option} = {shown} is invalid; valid: {self.choices}")


class EnvNotReset(EnvError):
    """``step`` (or ``render``) before the first ``reset``, or after the episode ended."""

    def __init__(self, what: str) -> None:
        super().__init__(f"{what}: call reset() first")
