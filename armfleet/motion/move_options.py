"""``avoid_collisions``, ``clearance_m``, ``timeout_s`` and ``budget`` of ``move_to``,
``move_to_pose`` and ``move_together``: one rule for the Python API, as the command line
and the live API apply it (a margin or a budget given without ``avoid_collisions=True``
is refused: the arm would move in a straight line, not what was asked).

A plan is bounded either by wall time (``timeout_s``, 1 s by default) or by work
(``budget``, RRT-Connect iterations): the same request with a budget gives the same
path in any process, on a busy machine or an idle one; with a timeout, a loaded machine
searches less. Giving both is refused.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from armfleet.checks.flags import flag
from armfleet.checks.number_ranges import PLANNING_BUDGET, PLANNING_TIMEOUT_S
from armfleet.errors import ArmfleetError

#: Default time budget of one planning request [s].
DEFAULT_TIMEOUT_S = 1.0
#: Default margin kept between different bodies by a planned move [m].
DEFAULT_CLEARANCE_M = 0.01
#: Planner iterations of each planned move of the shipped sweep scenarios (crossing,
#: handover): a budget, so that a run's row is the same on any machine under any load.
#: A two-Panda crossing needs tens to a few hundred; 2,000 is ~5 s of work at most.
SWEEP_BUDGET = 2000


@dataclass(frozen=True)
class PlanningLimit:
    """What bounds one planning request: wall time, or a number of iterations.

    Attributes:
        timeout_s: time budget [s]; not used when ``budget`` is given.
        budget: RRT-Connect iterations over the whole request, or None (time-bounded).
    """

    timeout_s: float = DEFAULT_TIMEOUT_S
    budget: int | None = None

    @classmethod
    def given(cls, timeout_s: object, budget: object) -> PlanningLimit:
        """The limit as a user gave it (None: not given).

        Raises:
            InvalidNumber: ``timeout_s`` not in [0.001, 60] s, or ``budget`` not an
                integer in 1..1000000.
            ArmfleetError: both given.
        """
        if budget is None:
            if timeout_s is None:
                return cls()
            return cls(PLANNING_TIMEOUT_S.check(timeout_s, "timeout_s"))
        if timeout_s is not None:
            raise ArmfleetError(
                "give timeout_s (wall time) or budget (planner iterations, reproducible), not both"
            )
        return cls(budget=int(PLANNING_BUDGET.check(budget, "budget")))

    def keywords(self) -> dict[str, Any]:
        """``timeout_s`` or ``budget``, as ``plan`` takes them."""
        return {"timeout_s": self.timeout_s} if self.budget is None else {"budget": self.budget}


@dataclass(frozen=True)
class MoveOptions:
    """How a move wants to move: planned (with its margin and limit) or straight."""

    avoid_collisions: bool
    clearance_m: float = DEFAULT_CLEARANCE_M
    limit: PlanningLimit = PlanningLimit()

    @property
    def timeout_s(self) -> float:
        return self.limit.timeout_s

    @property
    def budget(self) -> int | None:
        return self.limit.budget

    @classmethod
    def given(
        cls,
        avoid_collisions: object,
        clearance_m: float | None,
        timeout_s: float | None,
        budget: int | None = None,
    ) -> MoveOptions:
        """The options as a user gave them (None: not given).

        Raises:
            InvalidFlag: ``avoid_collisions`` is not a bool.
            InvalidNumber: ``timeout_s`` or ``budget`` out of range.
            ArmfleetError: a margin, timeout or budget without ``avoid_collisions=True``,
                or both a timeout and a budget.
        """
        if not flag(avoid_collisions, "avoid_collisions"):
            if clearance_m is not None or timeout_s is not None or budget is not None:
                raise ArmfleetError(
                    "clearance_m, timeout_s and budget go with avoid_collisions=True "
                    "(a planned move); without it the arm moves in a straight line"
                )
            return cls(False)
        return cls(
            True,
            DEFAULT_CLEARANCE_M if clearance_m is None else clearance_m,
            PlanningLimit.given(timeout_s, budget),
        )

    def plan_keywords(self) -> dict[str, Any]:
        """``clearance_m`` and ``timeout_s`` or ``budget``, as ``plan`` takes them."""
        return {"clearance_m": self.clearance_m, **self.limit.keywords()}
