"""Collision-free motion for one arm or several in a shared world.

- :mod:`~armfleet.planning.scene`: the world as one Pinocchio model with coal geometry;
- :mod:`~armfleet.planning.problem`: a request made concrete (:class:`PlanningProblem`);
- :mod:`~armfleet.planning.path_search`: OMPL's search, then the proof of clearance;
- :mod:`~armfleet.planning.path_timing`: timing within every joint's limits;
- :mod:`~armfleet.planning.moving_arms`: arms that move while a plan is made;
- :mod:`~armfleet.planning.motion_planner`: the world's planner (plan, execute).

Rule: imports :mod:`armfleet.motion`, :mod:`armfleet.objects`,
:mod:`armfleet.controllers` and below; arms are seen through the
:class:`~armfleet.planning.planned_arm.PlannedArm` protocol, never the user's handle.
"""

from armfleet.motion.pose_goal import PoseGoal
from armfleet.planning.failure import FailureReason, PlanningFailed
from armfleet.planning.motion_planner import MotionPlanner
from armfleet.planning.plan import Plan
from armfleet.planning.problem import PlanningProblem
from armfleet.planning.scene import PlanningScene

__all__ = [
    "FailureReason",
    "MotionPlanner",
    "Plan",
    "PlanningFailed",
    "PlanningProblem",
    "PlanningScene",
    "PoseGoal",
]
