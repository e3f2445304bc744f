"""Reach: a row of Pandas sent to random reachable tool poses, all at once.

The task spawns ``arm_count`` Pandas (``arm0``, ``arm1``, ...) in a row along x,
``spacing_m`` apart, all facing +y. A Panda's first joint turns ±166 degrees, so its
reachable space is nearly the same whichever way its base faces; facing one way makes
every arm's surroundings the same (a neighbour on either side, at ``spacing_m``), so the
spacing alone decides how much neighbours' spaces overlap, and arms at home stand side
by side, clear of each other even at a small spacing.

Each arm gets ``targets_per_arm`` random reachable targets
(:func:`~armfleet.scenarios.reach_targets.draw_targets`: the tool0 pose of a
random joint configuration clear of the limits, the floor and the arm itself). Round
by round, every arm is sent its next target as a Cartesian goal (``move_to_pose``: IK
from where the arm is, then a jerk-limited joint motion) on the same step; the world
runs the longest of the motions plus ``settle_s``, then each tool0 (from ``world.tf``)
is compared with its target. From home a motion takes 0.7-2.0 s (median 1.4 s; the
farthest joint moves up to 3.6 rad).

Physical failures are outcomes, not errors: IK that does not converge (the target is not
sent), a goal refused because the arm would touch itself at IK's solution or on the way
there (not sent: a redundant arm's solution need not be the drawn, clear configuration),
and protective stops (a neighbour, the arm itself or the floor touched on the
way). An arm in protective stop stays there: its later targets are not sent (no reset).

The arms are Pandas unless ``model`` names another: a shipped model, one's own by name, or
a model file (docs/own-robot.md; a sweep's workers read it, so give an absolute path or a
``package://`` URI there).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from armfleet.arms.arm import Arm
from armfleet.checks.real_numbers import real_number
from armfleet.errors import (
    ArmfleetError,
    InvalidNumber,
    ProtectiveStopError,
    SelfContactError,
    UnreachablePose,
)
from armfleet.scenarios.reach_targets import Target, draw_row_targets, pose_error
from armfleet.scenarios.tracking_monitor import TrackingMonitor
from armfleet.world import World

Metrics = dict[str, bool | int | float | str]

MODEL = "panda"
#: Yaw of every base: facing +y [deg].
FACING_DEG = 90.0


@dataclass(frozen=True)
class TargetResult:
    """How close an arm came to one target.

    Attributes:
        target: the target.
        sent: whether the goal went out (IK converged and the arm was not stopped).
        position_error_m: tool0's distance from the target when the round ended [m].
        rotation_error_rad: tool0's angle from the target's orientation then [rad].
    """

    target: Target
    sent: bool
    position_error_m: float
    rotation_error_rad: float

    def reached(self, tolerance_m: float, tolerance_rad: float) -> bool:
        return self.position_error_m <= tolerance_m and self.rotation_error_rad <= tolerance_rad


@dataclass(frozen=True)
class ReachOutcome:
    """What the arms did with their targets.

    Attributes:
        results: per target, in rounds, arm by arm within a round.
        ik_failures: goals not sent because IK did not converge.
        self_contact_refusals: goals not sent because the arm would touch itself at IK's
            solution or on the way (:class:`~armfleet.errors.SelfContactError`).
        stops: protective stops during the rounds.
        max_tracking_error_rad: largest ``|q_ref - q|`` of the position controllers
            during the rounds (:mod:`~armfleet.scenarios.tracking_monitor`) [rad].
    """

    results: tuple[TargetResult, ...]
    ik_failures: int
    self_contact_refusals: int
    stops: int
    max_tracking_error_rad: float

    def metrics(self, arms: int, tolerance_m: float, tolerance_deg: float) -> Metrics:
        """The task's metrics (see :func:`reach`)."""
        tolerance_rad = math.radians(tolerance_deg)
        reached = sum(r.reached(tolerance_m, tolerance_rad) for r in self.results)
        return {
            "arms": arms,
            "targets": len(self.results),
            "reached_fraction": reached / len(self.results) if self.results else math.nan,
            "ik_failures": self.ik_failures,
            "self_contact_refusals": self.self_contact_refusals,
            "stops": self.stops,
            "max_tracking_error_rad": self.max_tracking_error_rad,
            "max_position_error_m": max((r.position_error_m for r in self.results), default=0.0),
            "max_rotation_error_deg": math.degrees(
                max((r.rotation_error_rad for r in self.results), default=0.0)
            ),
        }


def reach(
    world: World,
    rng: np.random.Generator,
    *,
    arm_count: int = 2,
    spacing_m: float = 1.0,
    targets_per_arm: int = 1,
    settle_s: float = 0.2,
    limit_margin: float = 0.1,
    min_tool_height_m: float = 0.1,
    tolerance_m: float = 0.005,
    tolerance_deg: float = 2.0,
    model: str = MODEL,
) -> Metrics:
    """Spawn a row of arms (Pandas by default) and send each to random reachable tool
    poses, all at once.

    Args:
        world: the launched world (empty, or without arms named ``arm<i>``).
        rng: the run's generator (draws the targets).
        arm_count: Pandas in the row, >= 1.
        spacing_m: distance between neighbouring bases along x [m], > 0.
        targets_per_arm: targets per arm, one per round, >= 1.
        settle_s: time run after the longest motion of a round [s], >= 0.
        limit_margin: fraction of each joint's range kept clear of its limits.
        min_tool_height_m: lowest tool0 height of a target [m].
        tolerance_m, tolerance_deg: a target counts as reached when tool0 ends within
            this distance [m] and angle [deg] of it.
        model: the arms' model: a shipped model, one's own by name, or a model file.

    Returns:
        ``arms`` (int), ``targets`` (int, all arms), ``reached_fraction`` (reached
        targets / targets), ``ik_failures`` (int), ``self_contact_refusals`` (goals
        refused because the arm would touch itself, int), ``stops`` (protective stops, int),
        ``max_tracking_error_rad`` (largest ``|q_ref - q|`` of any joint of any arm
        after any step of the rounds: the position controller's Ruckig reference against
        the measured position at the same instant) [rad],
        ``max_position_error_m`` [m] and ``max_rotation_error_deg`` [deg] (the worst
        target's tool0 error at the end of its round).

    Raises:
        ArmfleetError: a bad parameter, or a spacing at which the arms touch at home
            (StartPoseCollision): a spec or sweep to fix, not an outcome.
    """
    count = _whole(targets_per_arm, "targets_per_arm")
    arms = spawn_row(world, arm_count, spacing_m, model)
    targets = draw_row_targets(
        arms, rng, count, limit_margin=limit_margin, min_tool_height_m=min_tool_height_m
    )
    outcome = reach_targets(world, targets, settle_s=settle_s)
    return outcome.metrics(len(arms), tolerance_m, tolerance_deg)


def spawn_row(world: World, count: int, spacing_m: float, model: str = MODEL) -> list[Arm]:
    """``count`` arms of ``model`` (Pandas by default) ``arm0``, ``arm1``, ... at x = 0,
    ``spacing_m``, ..., y = 0, facing +y."""
    count = _whole(count, "arm_count")
    spacing_m = real_number(
        spacing_m, "spacing_m", "a distance in [0.01, 100] m", low=0.01, high=100
    )
    return [
        world.spawn(f"arm{i}", model, at=(i * spacing_m, 0.0, 0.0, FACING_DEG))
        for i in range(count)
    ]


def reach_targets(
    world: World, targets: Mapping[str, Sequence[Target]], *, settle_s: float = 0.2
) -> ReachOutcome:
    """Send every arm its targets, one per round, all arms on the same step; each round
    lasts the longest motion plus ``settle_s`` [s].

    Args:
        world: the world holding the arms.
        targets: per arm name, its targets in order (as many for every arm).
    """
    settle_s = real_number(settle_s, "settle_s", "a time in [0, 60] s", low=0.0, high=60.0)
    rounds = {len(arm_targets) for arm_targets in targets.values()}
    if len(rounds) > 1:
        raise ArmfleetError(f"every arm needs as many targets, got {sorted(rounds)}")
    arms = [world.arm(name) for name in targets]
    results: list[TargetResult] = []
    ik_failures, refusals, stops_before = 0, 0, world.safety.stops
    monitor = TrackingMonitor(arms)
    for index in range(rounds.pop() if rounds else 0):
        sent: dict[str, bool] = {}
        durations = [0.0]
        for arm in arms:  # all between two steps: the motions start on the same step
            try:
                durations.append(arm.move_to_pose(targets[arm.name][index].pose))
                sent[arm.name] = True
            except UnreachablePose:
                ik_failures += 1
                sent[arm.name] = False
            except SelfContactError:
                refusals += 1
                sent[arm.name] = False
            except ProtectiveStopError:  # stopped in an earlier round, and left so
                sent[arm.name] = False
        world.run(max(durations) + settle_s, on_step=monitor.on_step)
        for arm in arms:
            target = targets[arm.name][index]
            tool = world.tf.lookup("world", arm.description.tool0)
            error_m, error_rad = pose_error(tool, target.pose)
            results.append(TargetResult(target, sent[arm.name], error_m, error_rad))
    stops = world.safety.stops - stops_before
    return ReachOutcome(tuple(results), ik_failures, refusals, stops, monitor.max_error_rad)


def _whole(value: object, name: str) -> int:
    """``value`` as a whole number in [1, 1000] (an int, or a float such as 2.0 from YAML)."""
    valid = "a whole number in [1, 1000]"
    number = real_number(value, name, valid, low=1.0, high=1000.0)
    if number != int(number):
        raise InvalidNumber(name, value, valid)
    return int(number)
