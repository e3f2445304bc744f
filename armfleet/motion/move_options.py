"""``avoid_collisions``, ``clearance_m`` and ``timeout_s`` of ``move_to``, ``move_to_pose``
and ``move_together``: one rule for the Python API, as the command line and the live API
apply it (a margin or a budget given without ``avoid_collisions=True`` is refused: the
arm would move in a straight line, not what was asked)."""

from __future__ import annotations

from dataclasses import dataclass

from armfleet.checks.flags import flag
from armfleet.errors import ArmfleetError

#: Default time budget of one planning request [s].
DEFAULT_TIMEOUT_S = 1.0
#: Default margin kept between different bodies by a planned move [m].
DEFAULT_CLEARANCE_M = 0.01


@dataclass(frozen=True)
class MoveOptions:
    """How a move wants to move: planned (with its margin and budget) or straight."""

    avoid_collisions: bool
    clearance_m: float = DEFAULT_CLEARANCE_M
    timeout_s: float = DEFAULT_TIMEOUT_S

    @classmethod
    def given(
        cls, avoid_collisions: object, clearance_m: float | None, timeout_s: float | None
    ) -> MoveOptions:
        """The options as a user gave them (None: not given).

        Raises:
            InvalidFlag: ``avoid_collisions`` is not a bool.
            ArmfleetError: a margin or budget without ``avoid_collisions=True``.
        """
        if not flag(avoid_collisions, "avoid_collisions"):
            if clearance_m is not None or timeout_s is not None:
                raise ArmfleetError(
                    "clearance_m and timeout_s go with avoid_collisions=True (a planned move); "
                    "without it the arm moves in a straight line"
                )
            return cls(False)
        return cls(
            True,
            DEFAULT_CLEARANCE_M if clearance_m is None else clearance_m,
            DEFAULT_TIMEOUT_S if timeout_s is None else timeout_s,
        )
