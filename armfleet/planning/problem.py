"""A planning request made concrete, before any planner sees it.

A continuous joint (no position limit) is searched over a window instead of its limits:
from half a turn below the lower of its start and goal to half a turn above the higher,
so it can swing either way out of something's way, but its goal is one number: the
planner sets it to the equivalent of the asked angle nearest the start
(:func:`~armfleet.kinematics.continuous_joints.nearest_turn`), and the move takes the
short way round.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from armfleet.messages import FloatArray
from armfleet.motion.move_options import DEFAULT_TIMEOUT_S
from armfleet.planning.scene import CollisionChecker


@dataclass(frozen=True)
class PlanningProblem:
    """Move ``arms`` from ``start`` to ``goal`` without leaving the clearance.

    The state is the arms' controlled joints (``Arm.joint_names``), concatenated in the
    order of ``arms``; every other joint, arm and object stands where the scene has it.

    Attributes:
        arms: the planned arms.
        start, goal: states [rad or m].
        lower, upper: the box the search samples [rad or m]: the joint position limits,
            and a continuous joint's window (:func:`search_bounds`); always finite.
        checker: collision checks against the scene snapshot taken for this request.
        timeout_s: time budget of the search [s] (wall time), when there is no
            ``budget``.
        budget: RRT-Connect iterations the search may run, over all its attempts; when
            given, it bounds the search instead of ``timeout_s``, and the path is the
            same for the same problem in any process, under any load.
    """

    arms: tuple[str, ...]
    start: FloatArray
    goal: FloatArray
    lower: FloatArray
    upper: FloatArray
    checker: CollisionChecker
    timeout_s: float = DEFAULT_TIMEOUT_S
    budget: int | None = None

    @property
    def dimension(self) -> int:
        return int(self.start.size)

    @property
    def clearance_m(self) -> float:
        return self.checker.scene.clearance_m

    @property
    def limit(self) -> str:
        """What bounds the search, as a keyword: ``budget=500`` or ``timeout_s=1``."""
        if self.budget is not None:
            return f"budget={self.budget}"
        return f"timeout_s={self.timeout_s:g}"

    def __repr__(self) -> str:
        return (
            f"PlanningProblem(arms={self.arms}, start={np.round(self.start, 4).tolist()}, "
            f"goal={np.round(self.goal, 4).tolist()}, clearance_m={self.clearance_m}, "
            f"{self.limit})"
        )


def search_bounds(
    lower: FloatArray,
    upper: FloatArray,
    continuous: npt.NDArray[np.bool_],
    start: FloatArray,
    goal: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """The box a search samples: the joint limits ``lower`` and ``upper`` [rad or m]; for a
    ``continuous`` joint (limits -inf and +inf), from half a turn below the lower of its
    ``start`` and ``goal`` to half a turn above the higher: every angle at least once."""
    low = np.where(continuous, np.minimum(start, goal) - np.pi, lower)
    high = np.where(continuous, np.maximum(start, goal) + np.pi, upper)
    return low, high
