"""Why a plan could not be made: :class:`PlanningFailed` and its :class:`FailureReason`."""

from __future__ import annotations

import enum
from typing import TYPE_CHECKING

from armfleet.errors import ArmfleetError

if TYPE_CHECKING:
    from armfleet.planning.problem import PlanningProblem


class FailureReason(enum.Enum):
    """The four ways a planning request fails."""

    START_IN_COLLISION = "start in collision"
    GOAL_IN_COLLISION = "goal in collision"
    GOAL_UNREACHABLE = "goal unreachable"
    NO_PATH = "no path found"


class PlanningFailed(ArmfleetError):
    """No collision-free motion was planned; nothing moved.

    Attributes:
        reason: which of the :class:`FailureReason` it is.
        arms: the arms of the request.
        links: for a start or goal in collision, the two bodies/links that are
            closer than the clearance (``("bob_panda_hand", "post")``); else ().
        samples: states the planner sampled (no path found), 0 otherwise.
        blocking_arm: an arm outside the request whose motion was in the way, or None.
        problem: the :class:`~armfleet.planning.problem.PlanningProblem`, when one was
            built (not for an unreachable pose goal), to replay or inspect.
    """

    def __init__(
        self,
        reason: FailureReason,
        detail: str,
        *,
        arms: tuple[str, ...],
        links: tuple[str, str] | tuple[()] = (),
        samples: int = 0,
        blocking_arm: str | None = None,
        problem: PlanningProblem | None = None,
    ) -> None:
        self.reason = reason
        self.arms = arms
        self.links = links
        self.samples = samples
        self.blocking_arm = blocking_arm
        self.problem = problem
        super().__init__(f"cannot plan {' + '.join(arms)}: {reason.value}: {detail}")
