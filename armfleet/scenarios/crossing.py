"""Crossing: two arms planned jointly past each other and a post, from random starts to
random goals.

The scene is ``launch_specs/crossing.yaml`` (the shared cell without its cubes): bob
and toby face each other over a table split at its middle by a post and two low walls;
a sweep moves the post about. Each run draws (:func:`draw_crossing`), per arm and in the
arm's own frame (``forward`` along the way it faces, ``left`` across), a tcp pose
pointing down, turned by up to :data:`TURN_DEG` from the arm's facing:

- its start above its own half of the table (:data:`NEAR_M` short of the middle),
- its goal above the other arm's half (:data:`FAR_M` beyond the middle),

each :data:`SIDE_M` to one side of the line between the bases and :data:`ABOVE_TABLE_M`
above the table. The side is drawn once for the starts and once for the goals, the same
in both arms' frames: in the world the two tools are then on opposite sides of the post,
so goals reached together never overlap, while an arm's start may be where the other's
goal is (a swap). Measured at the IK solutions nearest home of 600 such poses: the hands
keep 9 cm from the post in the middle (5 cm wherever it is within 3 cm of it), the
arms 5 cm from the walls and the table; at 4 % of them a forearm comes within 2 cm of
the post (8 mm into it at worst), where the planner takes another IK solution if it is
closer than the clearance. The walls stand in the way of a straight motion across.

:func:`cross` plans both arms jointly to their starts (from home) and runs the plan, then
plans them jointly to their goals (``world.plan``: 14 joints) and runs that. A plan not
found, a protective stop or a missed goal is an outcome, not an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from armfleet import topics
from armfleet.arms.arm import Arm
from armfleet.checks.real_numbers import real_number
from armfleet.messages import CollisionReport, FloatArray
from armfleet.motion.move_options import SWEEP_BUDGET, PlanningLimit
from armfleet.planning import Plan, PlanningFailed, PoseGoal
from armfleet.runtime.bus import Bus
from armfleet.scenarios.reach_targets import pose_error
from armfleet.world import World

Metrics = dict[str, bool | int | float | str]

ARMS = ("bob", "toby")
#: A start is this far short of the middle between the bases, along the arm's facing [m].
NEAR_M = (0.11, 0.19)
#: A goal is this far beyond the middle [m].
FAR_M = (0.11, 0.17)
#: Distance of a tcp from the line between the bases (the post's side) [m].
SIDE_M = (0.2, 0.35)
#: Height of a tcp above the table's top [m] (the walls stand 0.12 m high).
ABOVE_TABLE_M = (0.07, 0.17)
#: Largest turn of the hand about the vertical, from the arm's facing [deg].
TURN_DEG = 15.0
#: The tcp's z down and its x along the frame's x (a half turn about x).
DOWN = np.diag([1.0, -1.0, -1.0, 1.0])
#: Link of the poses.
LINK = "tcp"


@dataclass(frozen=True)
class Crossing:
    """One run's poses: per arm name, 4x4 world poses of its tcp.

    Attributes:
        starts: where the arms start, above their own halves of the table.
        goals: where they go, above the other arm's half.
    """

    starts: dict[str, FloatArray]
    goals: dict[str, FloatArray]


@dataclass
class CrossingOutcome:
    """What one run did; :meth:`metrics` are the task's metrics (see :func:`crossing`).

    Attributes:
        at_start: both arms got to their starts (no stop, within the tolerances).
        plan: the crossing's plan, or None (not made, or not asked for).
        failure: ``''``, or why the run is not a success (see :func:`crossing`).
        samples: states the crossing's search sampled (also of a failed one).
        stops: protective stops of the run.
        arm_contacts, obstacle_contacts: new contacts during the crossing.
        goal_errors_m, goal_errors_rad: per arm, its tcp's distance [m] and angle [rad]
            from its goal once the crossing ran (empty if it did not).
    """

    at_start: bool = False
    plan: Plan | None = None
    failure: str = ""
    samples: int = 0
    stops: int = 0
    arm_contacts: int = 0
    obstacle_contacts: int = 0
    goal_errors_m: list[float] = field(default_factory=list)
    goal_errors_rad: list[float] = field(default_factory=list)

    def metrics(self) -> Metrics:
        plan = self.plan
        return {
            "success": not self.failure,
            "failure": self.failure,
            "at_start": self.at_start,
            "planned": plan is not None,
            "planning_time_s": math.nan if plan is None else plan.planning_time_s,
            "samples": self.samples,
            "path_length_rad": math.nan if plan is None else plan.length_rad,
            "duration_s": math.nan if plan is None else plan.duration_s,
            "stops": self.stops,
            "arm_contacts": self.arm_contacts,
            "obstacle_contacts": self.obstacle_contacts,
            "goal_error_m": max(self.goal_errors_m, default=math.nan),
            "goal_error_deg": math.degrees(max(self.goal_errors_rad, default=math.nan)),
        }


class ContactTally:
    """Counts contacts of the arms as they start (on ``/collisions``), until :meth:`close`.

    Attributes:
        arm_contacts: new contacts between two different arms.
        obstacle_contacts: new contacts of an arm with itself, an object or the floor.
    """

    def __init__(self, bus: Bus, arms: tuple[str, ...]) -> None:
        self._arms = set(arms)
        self._touching: set[tuple[str, str]] = set()
        self.arm_contacts = 0
        self.obstacle_contacts = 0
        self._subscription = bus.subscribe(topics.COLLISIONS, self._on_report)

    def _on_report(self, report: CollisionReport) -> None:
        now: set[tuple[str, str]] = set()
        for contact in report.contacts:
            a, b = contact.body_a in self._arms, contact.body_b in self._arms
            if not (a or b):
                continue
            now.add(contact.pair)
            if contact.pair in self._touching:
                continue
            if a and b and contact.body_a != contact.body_b:
                self.arm_contacts += 1
            else:
                self.obstacle_contacts += 1
        self._touching = now

    def close(self) -> None:
        self._subscription.cancel()


def crossing(
    world: World,
    rng: np.random.Generator,
    *,
    timeout_s: float | None = None,
    budget: int | None = None,
    clearance_m: float = 0.01,
    settle_s: float = 0.2,
    tolerance_m: float = 0.001,
    tolerance_deg: float = 0.5,
) -> Metrics:
    """Move bob and toby to random starts, then plan them jointly across the table.

    Args:
        world: the launched crossing scene (arms ``bob`` and ``toby``, a ``table``).
        rng: the run's generator (draws the poses).
        timeout_s: time budget of each plan [s] (wall time: a loaded machine searches
            less, and its rows differ).
        budget: planner iterations of each plan instead (reproducible);
            :data:`~armfleet.motion.move_options.SWEEP_BUDGET` when neither is given.
        clearance_m: margin of the plans between different bodies [m].
        settle_s: time run after each plan's duration [s].
        tolerance_m, tolerance_deg: a goal is reached when the tcp ends within this
            distance [m] and angle [deg] of it (the controllers track to ~1e-6 rad).

    Returns:
        ``success`` (bool: both arms at their starts, the crossing planned and run with
        no protective stop and no contact, both goals reached); ``failure`` (str: ``''``
        on success, else the first reason: the :class:`~armfleet.FailureReason` name of
        the plan that failed (to the starts or across), ``PROTECTIVE_STOP``,
        ``START_MISSED``, ``CONTACT`` or ``GOAL_MISSED``); ``at_start`` (bool);
        ``planned`` (bool: the crossing plan was made); ``planning_time_s`` (its wall
        time [s], NaN without it); ``samples`` (states the crossing's search sampled, 0
        when the straight line was clear); ``path_length_rad`` (its joint-space length
        [rad], NaN); ``duration_s`` (its duration [s], NaN); ``stops`` (protective stops
        of the run); ``arm_contacts`` and ``obstacle_contacts`` (new contacts during the
        crossing between the arms, and of an arm with anything else); ``goal_error_m``
        [m] and ``goal_error_deg`` [deg] (the tcp farther from its goal after the
        crossing, NaN if it did not run).
    """
    return cross(
        world,
        draw_crossing(world, rng),
        timeout_s=timeout_s,
        budget=budget,
        clearance_m=clearance_m,
        settle_s=settle_s,
        tolerance_m=tolerance_m,
        tolerance_deg=tolerance_deg,
    ).metrics()


def draw_crossing(world: World, rng: np.random.Generator) -> Crossing:
    """The starts and goals of one run (see the module docstring), drawn with ``rng``."""
    arms = [world.arm(name) for name in ARMS]
    (x0, y0), (x1, y1) = ((arm.pose.x, arm.pose.y) for arm in arms)
    middle = 0.5 * math.hypot(x1 - x0, y1 - y0)
    table = world.object("table")
    top = float(table.position[2]) + 0.5 * table.size[2]
    start_side, goal_side = rng.choice([-1.0, 1.0], size=2)
    starts, goals = {}, {}
    for arm in arms:
        starts[arm.name] = _tcp_pose(
            arm,
            middle - rng.uniform(*NEAR_M),
            start_side * rng.uniform(*SIDE_M),
            top + rng.uniform(*ABOVE_TABLE_M),
            rng.uniform(-TURN_DEG, TURN_DEG),
        )
        goals[arm.name] = _tcp_pose(
            arm,
            middle + rng.uniform(*FAR_M),
            goal_side * rng.uniform(*SIDE_M),
            top + rng.uniform(*ABOVE_TABLE_M),
            rng.uniform(-TURN_DEG, TURN_DEG),
        )
    return Crossing(starts, goals)


def cross(
    world: World,
    poses: Crossing,
    *,
    timeout_s: float | None = None,
    budget: int | None = None,
    clearance_m: float = 0.01,
    settle_s: float = 0.2,
    tolerance_m: float = 0.001,
    tolerance_deg: float = 0.5,
) -> CrossingOutcome:
    """Plan and run the arms to ``poses.starts``, then jointly to ``poses.goals``.

    The keywords are :func:`crossing`'s. A plan not found, a stop or a missed pose ends
    the run early with its :attr:`CrossingOutcome.failure`; nothing is raised for them.
    """
    settle_s = real_number(settle_s, "settle_s", "a time in [0, 60] s", low=0.0, high=60.0)
    tolerance_rad = math.radians(tolerance_deg)
    if timeout_s is None and budget is None:
        budget = SWEEP_BUDGET
    limit = PlanningLimit.given(timeout_s, budget)
    outcome = CrossingOutcome()
    stops_before = world.safety.stops
    try:
        approach = _plan(world, poses.starts, clearance_m, limit)
    except PlanningFailed as exc:
        outcome.failure = exc.reason.name
        return outcome
    world.run(world.execute(approach) + settle_s)
    errors = [pose_error(_tcp(world, name), pose) for name, pose in poses.starts.items()]
    outcome.stops = world.safety.stops - stops_before
    if outcome.stops:
        outcome.failure = "PROTECTIVE_STOP"
        return outcome
    outcome.at_start = all(m <= tolerance_m and r <= tolerance_rad for m, r in errors)
    if not outcome.at_start:
        outcome.failure = "START_MISSED"
        return outcome
    try:
        outcome.plan = _plan(world, poses.goals, clearance_m, limit)
    except PlanningFailed as exc:
        outcome.failure, outcome.samples = exc.reason.name, exc.samples
        return outcome
    outcome.samples = outcome.plan.samples
    tally = ContactTally(world.bus, ARMS)
    try:
        world.run(world.execute(outcome.plan) + settle_s)
    finally:
        tally.close()
    outcome.stops = world.safety.stops - stops_before
    outcome.arm_contacts, outcome.obstacle_contacts = tally.arm_contacts, tally.obstacle_contacts
    for name, pose in poses.goals.items():
        error_m, error_rad = pose_error(_tcp(world, name), pose)
        outcome.goal_errors_m.append(error_m)
        outcome.goal_errors_rad.append(error_rad)
    if outcome.stops:
        outcome.failure = "PROTECTIVE_STOP"
    elif outcome.arm_contacts or outcome.obstacle_contacts:
        outcome.failure = "CONTACT"
    elif max(outcome.goal_errors_m) > tolerance_m or max(outcome.goal_errors_rad) > tolerance_rad:
        outcome.failure = "GOAL_MISSED"
    return outcome


def _plan(
    world: World, poses: dict[str, FloatArray], clearance_m: float, limit: PlanningLimit
) -> Plan:
    goals = {name: PoseGoal(pose, "world", LINK) for name, pose in poses.items()}
    return world.plan(goals, clearance_m=clearance_m, **limit.keywords())


def _tcp(world: World, arm: str) -> FloatArray:
    return world.tf.lookup("world", f"{arm}_{LINK}")


def _tcp_pose(arm: Arm, forward: float, left: float, z: float, turn_deg: float) -> FloatArray:
    """4x4 world pose of a tcp pointing down at (``forward``, ``left``) [m] in ``arm``'s
    frame, ``z`` [m] above the floor, its x turned ``turn_deg`` [deg] from the arm's facing."""
    yaw = math.radians(arm.pose.yaw_deg)
    heading = yaw + math.radians(turn_deg)
    pose = np.eye(4)
    pose[:3, 3] = (
        arm.pose.x + forward * math.cos(yaw) - left * math.sin(yaw),
        arm.pose.y + forward * math.sin(yaw) + left * math.cos(yaw),
        z,
    )
    pose[:2, :2] = [[math.cos(heading), -math.sin(heading)], [math.sin(heading), math.cos(heading)]]
    placed: FloatArray = pose @ DOWN
    return placed
