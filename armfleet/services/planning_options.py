"""``avoid_collisions``, ``clearance_m``, ``timeout_s`` and ``budget`` of the move requests
(``move``, ``move_pose``, ``move_together``), checked as the Python API checks them.

The flag must be a bool; the margin, the time budget and the budget of planner
iterations must lie in the ranges of :mod:`armfleet.checks.number_ranges`
(:data:`CLEARANCE_M`, :data:`PLANNING_TIMEOUT_S`, :data:`PLANNING_BUDGET`), the same
ranges the command line and the planner check. A margin or budget sent without
``avoid_collisions: true`` is refused: the arm would have moved in a straight line,
which is not what its sender asked for; so are ``timeout_s`` and ``budget`` together.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from armfleet.checks.number_ranges import (
    CLEARANCE_M,
    PLANNING_BUDGET,
    PLANNING_TIMEOUT_S,
    REQUEST_TIMEOUT_S,
)
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, MoveOptions, PlanningLimit
from armfleet.services.arguments import Arguments
from armfleet.services.errors import ProtocolError

#: The request fields of a collision-free move.
PLANNING_FIELDS = ("avoid_collisions", "clearance_m", "timeout_s", "budget")
#: Time the world may take beyond a plan's budget to answer (the scene, IK, the proof
#: of the path and its timing run around the search) [s].
PLANNING_REPLY_MARGIN_S = 2.0
#: How long a client waits per planner iteration of a ``budget`` [s]: a generous bound
#: (a two-Panda request in the shared cell took ~2.5 ms of CPU per iteration, proof
#: included, on the 2-core machine), so that a loaded world still answers in time.
PLANNING_WAIT_PER_ITERATION_S = 0.02


@dataclass(frozen=True)
class PlanningOptions:
    """How a move request wants to move.

    Attributes:
        avoid_collisions: plan around everything in the world instead of a straight line.
        clearance_m: margin kept from other bodies [m].
        limit: the plan's time budget [s] or budget of iterations.
    """

    avoid_collisions: bool = False
    clearance_m: float = DEFAULT_CLEARANCE_M
    limit: PlanningLimit = field(default_factory=PlanningLimit)

    @classmethod
    def from_request(cls, service: str, args: Arguments) -> PlanningOptions:
        """The options of a request of ``service``.

        Raises:
            ProtocolError: ``avoid_collisions`` is not a bool, a number is not in its
                range, a number came without ``avoid_collisions: true``, or both
                ``timeout_s`` and ``budget`` came.
        """
        avoid = bool(args.flag("avoid_collisions", False))
        clearance = args.in_range("clearance_m", None, CLEARANCE_M)
        timeout = args.in_range("timeout_s", None, PLANNING_TIMEOUT_S)
        budget = args.in_range("budget", None, PLANNING_BUDGET)
        if timeout is not None and budget is not None:
            raise ProtocolError(
                f"{service}: give 'timeout_s' (wall time) or 'budget' (planner iterations), "
                "not both"
            )
        if not avoid:
            for key in ("clearance_m", "timeout_s", "budget"):
                if args.has(key):
                    raise ProtocolError(
                        f"{service}: {key!r} goes with 'avoid_collisions': true (a planned "
                        "move); without it the arm moves in a straight line"
                    )
            return cls()
        limit = PlanningLimit.given(timeout, None if budget is None else int(budget))
        return cls(True, DEFAULT_CLEARANCE_M if clearance is None else clearance, limit)

    @property
    def work_s(self) -> float:
        """How long the world may work on the request once started [s]: the plan's time
        budget, or :data:`PLANNING_WAIT_PER_ITERATION_S` per iteration of its budget, and
        :data:`PLANNING_REPLY_MARGIN_S`; 0 for a straight move."""
        if not self.avoid_collisions:
            return 0.0
        budget = self.limit.budget
        if budget is None:
            return self.limit.timeout_s + PLANNING_REPLY_MARGIN_S
        work_s = min(REQUEST_TIMEOUT_S.high, budget * PLANNING_WAIT_PER_ITERATION_S)
        return work_s + PLANNING_REPLY_MARGIN_S

    def keywords(self) -> dict[str, Any]:
        """Keyword arguments of ``Arm.move_to``, ``Arm.move_to_pose`` and
        ``World.move_together``."""
        if not self.avoid_collisions:
            return {}
        return {"avoid_collisions": True, "clearance_m": self.clearance_m, **self.limit.keywords()}


def planning_request(
    avoid_collisions: bool,
    clearance_m: float,
    timeout_s: float | None,
    budget: int | None = None,
) -> tuple[dict[str, Any], float]:
    """The fields a client sends for these options, and how long the world may work on
    the request once it has started [s] (the plan's time budget, or
    :data:`PLANNING_WAIT_PER_ITERATION_S` per iteration of its ``budget``, and a margin;
    0 without ``avoid_collisions``).

    Raises:
        InvalidFlag, InvalidNumber: as the local API raises them; nothing is sent.
        ArmfleetError: both ``timeout_s`` and ``budget``, or either without
            ``avoid_collisions``; nothing is sent.
    """
    options = MoveOptions.given(avoid_collisions, None, timeout_s, budget)
    if not options.avoid_collisions:
        return {}, 0.0
    clearance = CLEARANCE_M.check(clearance_m, "clearance_m")
    planned = PlanningOptions(True, clearance, options.limit)
    return planned.keywords(), planned.work_s
