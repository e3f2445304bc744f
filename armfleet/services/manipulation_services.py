"""Services that manipulate: the gripper, Cartesian goals and time-synchronised moves
(each straight, or planned around obstacles: see :mod:`armfleet.services.planning_options`).

As in :mod:`armfleet.services.world_services`, each ``prepare_*`` checks the request in
the server thread and returns work for the stepping thread; the world's own
checks (unknown arm, no gripper, width out of range, unreachable pose...) raise
there, with the world's messages, and then nothing moves.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from armfleet.arms.arm import Arm
from armfleet.arms.gripper import Gripper
from armfleet.messages import GripperMode
from armfleet.motion.pose_goal import PoseGoal
from armfleet.services.arguments import Arguments
from armfleet.services.codec import to_wire
from armfleet.services.errors import ProtocolError
from armfleet.services.planned_move import planned_move
from armfleet.services.planning_options import PlanningOptions
from armfleet.world import World

Work = Callable[[], Any]

#: What ``grip`` does: open fully, close with a force, or go to ``width``.
GRIP_ACTIONS = ("open", "close", "width")
#: Fingers slower than this are at rest [m/s].
FINGERS_AT_REST_M_S = 1e-3
#: Simulated time the fingers may take to come to rest once their motion ended [s].
GRIPPER_SETTLE_S = 0.5
_MOVING = (GripperMode.MOVING, GripperMode.CLOSING)


class ManipulationServices:
    """``grip``, ``move_pose`` and ``move_together`` of one world (and the gripper's wait)."""

    def __init__(self, world: World) -> None:
        self._world = world

    def prepare_grip(self, args: Arguments) -> Work:
        name, world = args.text("name"), self._world
        action = args.text("action")
        if action not in GRIP_ACTIONS:
            raise ProtocolError(
                f"grip: action {action!r} is unknown; actions: {', '.join(GRIP_ACTIONS)}"
            )
        # Non-finite numbers pass: the gripper names the valid range in its own words.
        width: float = args.number("width", finite=False) if action == "width" else 0.0
        if action != "width" and args.has("width"):
            raise ProtocolError(f"grip: 'width' goes with action 'width', not {action!r}")
        force = args.number("force", None, finite=False)

        def grip() -> dict[str, Any]:
            gripper = world.arm(name).gripper
            if action == "open":
                gripper.open(force=force)
            elif action == "close":
                gripper.close(force=force)
            else:
                gripper.move_to(width, force=force)
            return describe_gripper(gripper, world.time)

        return grip

    def gripper_wait_check(self, name: str) -> Callable[[], dict[str, Any] | None]:
        """A check, run once per step, of whether ``name``'s fingers have stopped.

        It returns None while they move or close, then the gripper's state once the
        fingers are at rest (or have had :data:`GRIPPER_SETTLE_S` to come to rest).
        """
        world = self._world
        last: list[float] = []  # [time the motion ended, width at the previous check]

        def check() -> dict[str, Any] | None:
            gripper = world.arm(name).gripper
            width = gripper.width
            if gripper.mode in _MOVING:
                last.clear()
                return None
            if not last:
                last.extend((world.time, width))
                return None
            since, previous = last
            last[1] = width
            at_rest = abs(width - previous) <= FINGERS_AT_REST_M_S * world.dt
            if not at_rest and world.time - since < GRIPPER_SETTLE_S:
                return None
            return describe_gripper(gripper, world.time)

        return check

    def prepare_move_pose(self, args: Arguments) -> Work:
        name, world = args.text("name"), self._world
        if args.has("pose") == args.has("position"):
            raise ProtocolError(
                "move_pose: give 'pose' (16 numbers, a 4x4 matrix row by row) or 'position' "
                "(x, y, z, keeping the link's orientation), not both"
                if args.has("pose")
                else "move_pose: missing field 'pose' (16 numbers, a 4x4 matrix row by row) "
                "or 'position' (x, y, z)"
            )
        pose = _sized(args, "pose", 16) if args.has("pose") else None
        position = _sized(args, "position", 3) if args.has("position") else None
        frame, link = args.text("frame", "world"), args.text("link", "tool0")
        linear = args.flag("linear", False)
        options = PlanningOptions.from_request("move_pose", args).keywords()

        def moved(arm: Arm, duration: float) -> dict[str, Any]:
            return {"time_s": world.time, "duration_s": duration, "moving": arm.is_moving}

        def move_pose() -> Any:
            arm = world.arm(name)
            goal = (
                np.reshape(pose, (4, 4))
                if pose is not None
                else _keeping_orientation(world, arm, position, frame, link)
            )
            if options and not linear:  # planned off the stepping thread
                targets = {name: PoseGoal(goal, frame, link)}
                return planned_move(world, targets, options, partial(moved, arm))
            # linear together with avoid_collisions: the arm refuses it in its own words.
            return moved(arm, arm.move_to_pose(goal, frame, link=link, linear=linear, **options))

        return move_pose

    def prepare_move_together(self, args: Arguments) -> Work:
        raw = args.mapping("targets")
        if not raw:
            raise ProtocolError("move_together: 'targets' is empty; give {arm: [q1, q2, ...]}")
        checked = Arguments("move_together", raw, list(raw), label="'targets'")
        targets = {str(name): checked.vector(name) for name in raw}
        options = PlanningOptions.from_request("move_together", args).keywords()
        world = self._world

        def moved(duration: float) -> dict[str, Any]:
            return {"time_s": world.time, "duration_s": duration, "arms": list(targets)}

        def move_together() -> Any:
            if options:  # planned off the stepping thread
                return planned_move(world, targets, options, moved)
            return moved(world.move_together(targets))

        return move_together


def describe_gripper(gripper: Gripper, stamp: float) -> dict[str, Any]:
    """A gripper's state and limits, as ``grip`` and the arm descriptions report it."""
    state: dict[str, Any] = to_wire(gripper.state(stamp))
    return state | {
        "max_width": gripper.max_width,
        "max_force": gripper.max_force,
        "min_width": gripper.min_width,
        "width_unit": gripper.width_unit,
        "force_unit": gripper.force_unit,
    }


def _sized(args: Arguments, key: str, length: int) -> list[float]:
    values: list[float] = args.vector(key)
    if len(values) != length:
        raise ProtocolError(f"move_pose: {key!r} has {len(values)} numbers; give {length}")
    return values


def _keeping_orientation(
    world: World, arm: Arm, position: Any, frame: str, link: str
) -> np.ndarray[Any, Any]:
    """A goal at ``position`` in ``frame`` with the link's current orientation in it."""
    goal = np.eye(4)
    goal[:3, 3] = position
    prefix = arm.description.prefix
    name = link if link.startswith(prefix) else prefix + link
    if arm.kinematics.has_frame(name):  # else move_to_pose names the arm's links
        frame_rotation = world.tf.world_pose(frame)[:3, :3]
        goal[:3, :3] = frame_rotation.T @ world.tf.world_pose(name)[:3, :3]
    return goal
