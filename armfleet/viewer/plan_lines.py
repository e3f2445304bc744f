"""The tool path of each arm's planned motion, drawn as a line while the motion runs.

A collision-free plan announces itself on ``/<arm>/planned_motion``
(:class:`~armfleet.messages.PlannedMotion`) at the step it starts. Its
``tool_path`` (world positions of the arm's tool0) is drawn as a line at
``/meshcat/armfleet/<arm>/planned_motion``, and removed at the first tick after
the motion is over for any reason:

* its time is up (``stamp + duration``), or the arm, seen moving since the line
  was drawn, no longer moves;
* the arm is in protective stop;
* a target other than the plan's goal reached the arm's position controller
  (re-targeting; the target the planner itself publishes "for the record" is the
  goal and keeps the line);
* another planned motion of the arm replaces it;
* the arm leaves the viewer (its whole node goes with it).

The bus callbacks only note what happened (under a small lock: they run in
whatever thread publishes); the viewer's tick sends the MeshCat commands under
the viewer's lock. A world with no plan pays one truth test per step
(:attr:`PlanLines.busy`).
"""

from __future__ import annotations

import logging
import math
import threading
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from armfleet import topics
from armfleet.messages import FloatArray, JointCommand, PlannedMotion

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.runtime.bus import Subscription

logger = logging.getLogger("armfleet")

#: Colour of a planned tool path (magenta: apart from the grey arms, the blue-grey
#: background, the dark grid and the orange target marker).
PLAN_COLOR = 0xFF00C8
#: Line width in pixels (WebGL draws most lines 1 px wide whatever is asked).
PLAN_LINE_WIDTH = 3.0
#: Most points sent for one line; a longer path is thinned evenly (ends kept).
MAX_LINE_POINTS = 2000
#: A target this close to the plan's goal, joint by joint, is the plan's own [rad or m].
GOAL_TOLERANCE = 1e-9
#: Name of the line's node under the arm's node.
NODE = "planned_motion"


def line_points(tool_path: Any) -> npt.NDArray[np.float32] | None:
    """The line's points (3 x n, float32) from a plan's ``tool_path`` (n x 3 [m]).

    Returns None for a path that cannot be drawn: not n x 3 numbers with n >= 2,
    or holding a value that is not finite. Paths longer than
    :data:`MAX_LINE_POINTS` are thinned evenly, keeping both ends.
    """
    try:
        path = np.asarray(tool_path, dtype=float)
    except (TypeError, ValueError):
        return None
    if path.ndim != 2 or path.shape[1] != 3 or len(path) < 2 or not np.isfinite(path).all():
        return None
    if len(path) > MAX_LINE_POINTS:
        keep = np.unique(np.linspace(0, len(path) - 1, MAX_LINE_POINTS).round().astype(int))
        path = path[keep]
    points: npt.NDArray[np.float32] = np.ascontiguousarray(path.T, dtype=np.float32)
    return points


def plan_goal(plan: PlannedMotion) -> FloatArray | None:
    """The plan's last waypoint, or None if it has none readable."""
    try:
        positions = np.asarray(plan.positions, dtype=float)
    except (TypeError, ValueError):
        return None
    if positions.ndim != 2 or not len(positions):
        return None
    goal: FloatArray = positions[-1].copy()
    return goal


def plan_end_s(plan: PlannedMotion) -> float:
    """Simulated time the plan ends [s]; infinite if its stamp or duration is unusable."""
    try:
        end = float(plan.stamp) + float(plan.duration)
    except (TypeError, ValueError, IndexError):
        return math.inf
    return end if math.isfinite(end) else math.inf


class _Line:
    """A plan drawn (or about to be) for one arm, and what ends it."""

    __slots__ = ("controller", "end_s", "goal", "plan", "seen_moving")

    def __init__(self, plan: PlannedMotion, controller: Any) -> None:
        self.plan = plan
        self.goal = plan_goal(plan)
        self.end_s = plan_end_s(plan)
        #: The arm's position controller: ``is_moving`` and ``stop_reason`` are read.
        self.controller = controller
        self.seen_moving = False

    def over(self, time_s: float) -> bool:
        """Whether the motion is over at ``time_s``: its time is up, the arm is in
        protective stop, or the arm, seen moving since the line was drawn, stands still."""
        if time_s >= self.end_s:
            return True
        controller = self.controller
        if controller.stop_reason is not None:
            return True
        if controller.is_moving:
            self.seen_moving = True
            return False
        return self.seen_moving


class _Follower:
    """One arm's subscriptions."""

    def __init__(self, arm: Arm, owner: PlanLines) -> None:
        self.controller = arm.position_controller
        bus = self.controller.arm.bus
        name = arm.name
        self.subscriptions: list[Subscription] = [
            bus.subscribe(topics.planned_motion(arm.name), lambda plan: owner.on_plan(name, plan)),
            bus.subscribe(
                topics.position_commands(arm.name),
                lambda command: owner.on_command(name, command),
            ),
        ]

    def cancel(self) -> None:
        for subscription in self.subscriptions:
            subscription.cancel()
        self.subscriptions = []


class PlanLines:
    """The planned-motion lines of one viewer's arms.

    What it reads from an arm (a recording's replay passes look-alikes): ``name``,
    ``namespace`` and ``position_controller`` with ``arm.bus``, ``is_moving`` and
    ``stop_reason``.

    Args:
        visualizer: the viewer's ``meshcat.Visualizer`` (root ``/meshcat``).
    """

    def __init__(self, visualizer: Any) -> None:
        self._visualizer = visualizer
        self._lock = threading.Lock()
        self._followers: dict[str, _Follower] = {}
        #: Plans received and not drawn yet, newest per arm.
        self._incoming: dict[str, _Line] = {}
        #: Arms whose line must go at the next tick (re-targeted).
        self._cancelled: set[str] = set()
        #: Whether ``_incoming`` or ``_cancelled`` hold anything.
        self._events = False
        #: Lines on show; changed by the tick only, read by the callbacks under the lock.
        self._shown: dict[str, _Line] = {}
        #: The same, as the tick walks it.
        self._on_show: tuple[tuple[str, _Line], ...] = ()

    @property
    def busy(self) -> bool:
        """Whether a line is on show or something about one waits for the next tick."""
        return self._events or bool(self._on_show)

    @property
    def shown(self) -> dict[str, PlannedMotion]:
        """The plans whose line is on show, by arm."""
        return {name: line.plan for name, line in self._on_show}

    # -- arms --------------------------------------------------------------------------
    def follow(self, arm: Arm) -> None:
        """Draw ``arm``'s planned motions from now on."""
        follower = _Follower(arm, self)
        with self._lock:
            old = self._followers.pop(arm.name, None)
            self._followers[arm.name] = follower
        if old is not None:
            old.cancel()

    def forget(self, name: str) -> None:
        """Stop following arm ``name``; its node (line included) is the viewer's to delete."""
        with self._lock:
            follower = self._followers.pop(name, None)
            self._incoming.pop(name, None)
            self._cancelled.discard(name)
            self._events = bool(self._incoming or self._cancelled)
            self._shown.pop(name, None)
            self._shown_changed()
        if follower is not None:
            follower.cancel()

    def close(self) -> None:
        """Cancel every subscription; idempotent."""
        with self._lock:
            followers = list(self._followers.values())
            self._followers.clear()
            self._incoming.clear()
            self._cancelled.clear()
            self._events = False
            self._shown.clear()
            self._shown_changed()
        for follower in followers:
            follower.cancel()

    def _shown_changed(self) -> None:
        """Take a changed ``_shown`` into the tick's tuple (caller holds the lock)."""
        self._on_show = tuple(self._shown.items())

    # -- bus callbacks (any thread) -------------------------------------------------------
    def on_plan(self, name: str, plan: Any) -> None:
        """A plan starts on arm ``name``: its line replaces any other at the next tick."""
        if not isinstance(plan, PlannedMotion):
            return
        with self._lock:
            follower = self._followers.get(name)
            if follower is None:
                return
            self._incoming[name] = _Line(plan, follower.controller)
            self._cancelled.discard(name)
            self._events = True

    def on_command(self, name: str, command: Any) -> None:
        """A target reached arm ``name``'s controller: unless it is the plan's goal, the
        plan is abandoned (re-targeting) and its line goes at the next tick."""
        with self._lock:
            line = self._incoming.get(name) or self._shown.get(name)
            if line is None or _is_goal(command, line.goal):
                return
            self._incoming.pop(name, None)
            if name in self._shown:
                self._cancelled.add(name)
            self._events = bool(self._incoming or self._cancelled)

    # -- tick (the viewer's thread, under its lock) ---------------------------------------
    def update(self, time_s: float) -> None:
        """Send the lines' changes due at simulated time ``time_s`` [s].

        Raises:
            ViewerError: the server did not take a command.
        """
        if self._events:
            self._take_events()
        for name, line in self._on_show:
            if line.over(time_s):
                with self._lock:
                    if self._shown.get(name) is line:
                        del self._shown[name]
                        self._shown_changed()
                self._delete(name)

    def _take_events(self) -> None:
        with self._lock:
            cancelled, self._cancelled = self._cancelled, set()
            incoming, self._incoming = self._incoming, {}
            self._events = False
            # A replaced line goes with the new one's set_object, not with a delete.
            gone = [n for n in cancelled if n not in incoming and n in self._shown]
            for name in gone:
                del self._shown[name]
            self._shown_changed()
        for name in gone:
            self._delete(name)
        for name, line in incoming.items():
            self._draw(name, line)

    def _delete(self, name: str) -> None:
        self._visualizer[f"armfleet/{name}/{NODE}"].delete()

    def _draw(self, name: str, line: _Line) -> None:
        import meshcat.geometry as mg

        points = line_points(line.plan.tool_path)
        if points is None:
            logger.warning("viewer: %s's planned motion has no drawable tool path", name)
            with self._lock:
                had = self._shown.pop(name, None)
                self._shown_changed()
            if had is not None:
                self._delete(name)
            return
        material = mg.LineBasicMaterial(color=PLAN_COLOR, linewidth=PLAN_LINE_WIDTH)
        node = self._visualizer[f"armfleet/{name}/{NODE}"]
        node.set_object(mg.Line(mg.PointsGeometry(points), material))
        with self._lock:
            if name in self._followers:  # not forgotten meanwhile
                self._shown[name] = line
                self._shown_changed()


def _is_goal(command: Any, goal: FloatArray | None) -> bool:
    """Whether ``command`` targets ``goal`` (the plan's own target)."""
    if goal is None or not isinstance(command, JointCommand):
        return False
    try:
        target = np.asarray(command.positions, dtype=float)
    except (TypeError, ValueError):
        return False
    return bool(target.shape == goal.shape and np.all(np.abs(target - goal) <= GOAL_TOLERANCE))
