"""``avoid_collisions``, ``clearance_m`` and ``timeout_s`` of the move requests (``move``,
``move_pose``, ``move_together``), checked as the Python API checks them.

The flag must be a bool; the margin and the time budget must lie in the ranges of
:mod:`armfleet.checks.number_ranges` (:data:`CLEARANCE_M`, :data:`PLANNING_TIMEOUT_S`),
the same ranges the command line and the planner check. A margin or budget sent
without ``avoid_collisions: true`` is refused: the arm would have moved in a straight
line, which is not what its sender asked for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from armfleet.checks.flags import flag
from armfleet.checks.number_ranges import CLEARANCE_M, PLANNING_TIMEOUT_S
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, DEFAULT_TIMEOUT_S
from armfleet.services.arguments import Arguments
from armfleet.services.errors import ProtocolError

#: The request fields of a collision-free move.
PLANNING_FIELDS = ("avoid_collisions", "clearance_m", "timeout_s")
#: Time the world may take beyond a plan's budget to answer (the scene, IK, the proof
#: of the path and its timing run around the search) [s].
PLANNING_REPLY_MARGIN_S = 2.0


@dataclass(frozen=True)
class PlanningOptions:
    """How a move request wants to move.

    Attributes:
        avoid_collisions: plan around everything in the world instead of a straight line.
        clearance_m: margin kept from other bodies [m].
        timeout_s: time budget of the plan [s].
    """

    avoid_collisions: bool = False
    clearance_m: float = DEFAULT_CLEARANCE_M
    timeout_s: float = DEFAULT_TIMEOUT_S

    @classmethod
    def from_request(cls, service: str, args: Arguments) -> PlanningOptions:
        """The options of a request of ``service``.

        Raises:
            ProtocolError: ``avoid_collisions`` is not a bool, a number is not in its
                range, or a number came without ``avoid_collisions: true``.
        """
        avoid = bool(args.flag("avoid_collisions", False))
        clearance = args.in_range("clearance_m", None, CLEARANCE_M)
        timeout = args.in_range("timeout_s", None, PLANNING_TIMEOUT_S)
        if not avoid:
            for key in ("clearance_m", "timeout_s"):
                if args.has(key):
                    raise ProtocolError(
                        f"{service}: {key!r} goes with 'avoid_collisions': true (a planned "
                        "move); without it the arm moves in a straight line"
                    )
            return cls()
        return cls(
            True,
            DEFAULT_CLEARANCE_M if clearance is None else clearance,
            DEFAULT_TIMEOUT_S if timeout is None else timeout,
        )

    def keywords(self) -> dict[str, Any]:
        """Keyword arguments of ``Arm.move_to``, ``Arm.move_to_pose`` and
        ``World.move_together``."""
        if not self.avoid_collisions:
            return {}
        return {
            "avoid_collisions": True,
            "clearance_m": self.clearance_m,
            "timeout_s": self.timeout_s,
        }


def planning_request(
    avoid_collisions: bool, clearance_m: float, timeout_s: float
) -> tuple[dict[str, Any], float]:
    """The fields a client sends for these options, and how long the world may work on
    the request once it has started [s] (the plan's budget and a margin; 0 without one).

    Raises:
        InvalidFlag, InvalidNumber: as the local API raises them; nothing is sent.
    """
    if not flag(avoid_collisions, "avoid_collisions"):
        return {}, 0.0
    clearance = CLEARANCE_M.check(clearance_m, "clearance_m")
    budget = PLANNING_TIMEOUT_S.check(timeout_s, "timeout_s")
    fields = {"avoid_collisions": True, "clearance_m": clearance, "timeout_s": budget}
    return fields, budget + PLANNING_REPLY_MARGIN_S
