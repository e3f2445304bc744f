"""Collision-free motion for one arm or several in a shared world.

- :mod:`~armfleet.planning.scene`: the world as one Pinocchio model with coal geometry;
- :mod:`~armfleet.planning.compiled_check`: the scene's checks and proof in compiled code;
- :mod:`~armfleet.planning.problem`: a request made concrete (:class:`PlanningProblem`);
- :mod:`~armfleet.planning.path_search`: OMPL's search, then the proof of clearance;
- :mod:`~armfleet.planning.path_timing`: timed segments, and the rest-to-rest reference;
- :mod:`~armfleet.planning.smooth_timing`: through the waypoints without stopping;
- :mod:`~armfleet.planning.curve_check`: the proof of clearance for the executed curve;
- :mod:`~armfleet.planning.moving_arms`: arms that move while a plan is made;
- :mod:`~armfleet.planning.planning_request`: a request read from the world, plannable on
  any thread; :mod:`~armfleet.planning.scene_pool`: a scene of its own for each;
- :mod:`~armfleet.planning.motion_planner`: the world's planner (prepare, solve, plan,
  execute).

Rule: imports :mod:`armfleet.motion`, :mod:`armfleet.objects`,
:mod:`armfleet.controllers` and below; arms are seen through the
:class:`~armfleet.planning.planned_arm.PlannedArm` protocol, never the user's handle.
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.motion.pose_goal import PoseGoal
    from armfleet.planning.failure import FailureReason, PlanningFailed
    from armfleet.planning.motion_planner import MotionPlanner
    from armfleet.planning.plan import Plan
    from armfleet.planning.problem import PlanningProblem
    from armfleet.planning.scene import PlanningScene

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "PoseGoal": "armfleet.motion.pose_goal",
        "FailureReason": "armfleet.planning.failure",
        "PlanningFailed": "armfleet.planning.failure",
        "MotionPlanner": "armfleet.planning.motion_planner",
        "Plan": "armfleet.planning.plan",
        "PlanningProblem": "armfleet.planning.problem",
        "PlanningScene": "armfleet.planning.scene",
    },
)

__all__ = [
    "FailureReason",
    "MotionPlanner",
    "Plan",
    "PlanningFailed",
    "PlanningProblem",
    "PlanningScene",
    "PoseGoal",
]
