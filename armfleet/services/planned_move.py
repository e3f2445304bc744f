"""A move request with ``avoid_collisions``: planned off the stepping thread.

The request's work (run on the stepping thread) only reads the world and hands the
search to a worker thread (:meth:`armfleet.World.start_planned_move`); it returns a
:class:`~armfleet.runtime.request_queue.Deferred`, and the request is answered when the
motion starts, or the plan fails. Meanwhile the world steps and serves every other
request.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from armfleet.runtime.request_queue import Deferred
from armfleet.world import World

T = TypeVar("T")


def planned_move(
    world: World,
    targets: Mapping[str, Any],
    keywords: Mapping[str, Any],
    reply: Callable[[float], T],
) -> Deferred[T]:
    """Plan ``targets`` (per arm: joint positions, a 4x4 world pose of tool0, or a
    :class:`~armfleet.motion.pose_goal.PoseGoal`) with ``keywords`` (of
    :meth:`~armfleet.services.planning_options.PlanningOptions.keywords`) off the stepping
    thread; the answer is ``reply(duration)`` once the motion starts. Run it on the
    stepping thread.

    Raises:
        ArmfleetError: the world refuses the request as it reads it (unknown arm, a moving
            arm, a bad target); nothing moves.
    """
    options = {key: value for key, value in keywords.items() if key != "avoid_collisions"}
    return world.start_planned_move(targets, reply, **options)
