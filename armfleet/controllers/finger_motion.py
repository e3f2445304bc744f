"""A gripper's fingers planned to a new opening from wherever their reference is.

The fingers of a parallel gripper (the Panda's two) are planned together, so that they
start and finish at once. Ruckig synchronises them by stretching the shorter motions to
the longest one's duration, and that stretch fails numerically ("error in step 2")
when the fingers' motions are almost, but not exactly, as long: two fingers cruising
at their speed limit, ~1e-7 s apart, sent back the way they came. Random open and close
commands at a 20 ms control period met such a state about once in 200,000 commands
(``tests/test_finger_motion.py`` keeps one), and the command was lost (older versions
faulted the arm with a ``RuckigError``). Such a motion is planned again to finish
together one controller period after the slowest finger alone would, a stretch Ruckig
solves; the command is then always taken.
"""

from __future__ import annotations

import ruckig

from armfleet.controllers.jerk_limited_trajectory import (
    JerkLimitedTrajectory,
    MotionPlan,
    TrajectoryError,
    calculate,
)
from armfleet.messages import FloatArray


def plan_fingers(
    trajectory: JerkLimitedTrajectory,
    target: FloatArray,
    limits: tuple[FloatArray, FloatArray, FloatArray],
    period: float,
) -> MotionPlan:
    """Plan the fingers from their reference state to rest at ``target``.

    Args:
        trajectory: the fingers' reference.
        target: each leader's position [m, or rad].
        limits: each leader's speed, acceleration and jerk limits.
        period: the controller's period [s].

    Raises:
        TrajectoryError: a finger alone cannot be planned (not seen: Ruckig's
            single-joint cases are covered by :func:`calculate`'s nudges).
    """
    try:
        return trajectory.plan(target)
    except TrajectoryError:
        pass  # the synchronisation failed: finish a little later, together
    slowest = max(
        _alone(trajectory, index, float(target[index]), limits, period)
        for index in range(len(target))
    )
    return trajectory.plan(target, minimum_duration_s=slowest + period)


def _alone(
    trajectory: JerkLimitedTrajectory,
    index: int,
    target: float,
    limits: tuple[FloatArray, FloatArray, FloatArray],
    period: float,
) -> float:
    """How long finger ``index`` takes to reach ``target`` on its own [s]."""
    speed, acceleration, jerk = limits
    motion = ruckig.InputParameter(1)
    motion.current_position = [float(trajectory.position[index])]
    motion.current_velocity = [float(trajectory.velocity[index])]
    motion.current_acceleration = [float(trajectory.acceleration[index])]
    motion.target_position = [target]
    motion.target_velocity = [0.0]
    motion.target_acceleration = [0.0]
    motion.max_velocity = [float(speed[index])]
    motion.max_acceleration = [float(acceleration[index])]
    motion.max_jerk = [float(jerk[index])]
    result = ruckig.Trajectory(1)
    outcome = calculate(ruckig.Ruckig(1, period), motion, result)
    if outcome not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise TrajectoryError(f"Ruckig cannot plan a finger's motion: {outcome}")
    return float(result.duration)
