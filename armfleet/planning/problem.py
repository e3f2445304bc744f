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
        timeout_s: time budget of the search [s].
    """

    arms: tuple[str, ...]
    start: FloatArray
    goal: FloatArray
    lower: FloatArray
    upper: FloatArray
    checker: CollisionChecker
    timeout_s: float = DEFAULT_TIMEOUT_S

    @property
    def dimension(self) -> int:
        return int(self.start.size)

    @property
    def clearance_m(self) -> float:
        return self.checker.scene.clearance_m

    def __repr__(self) -> str:
        return (
            f"PlanningProblem(arms={self.arms}, start={np.round(self.start, 4).tolist()}, "
            f"goal={np.round(self.goal, 4).tolist()}, clearance_m={self.clearance_m}, "
            f"timeout_s={self.timeout_s})"
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
