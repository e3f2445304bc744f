"""A planning request made concrete, before any planner sees it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
        lower, upper: joint position limits of the state.
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
