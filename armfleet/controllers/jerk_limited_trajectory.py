"""Jerk-limited joint motion with Ruckig, re-planned from the current reference state.

Besides Ruckig's own motions, the reference can follow a sampled motion (one
position, velocity and acceleration per period, e.g. a straight tool line);
a stop or a new plan takes over from wherever that reference is.

Motions are planned with Ruckig's Python bindings. Where armfleet's compiled part is
built, they are stepped by Ruckig's C++ library directly into the reference arrays
(``cpp/reference_stepper.cpp``'s ``ReferenceStepper``: no Python lists per step); else,
or with ``compiled=False``, by the bindings' ``update``. Both run the same algorithm
on the same input (``tests/test_fleet_update.py`` compares whole runs).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import ruckig

from armfleet.errors import ArmfleetError
from armfleet.messages import FloatArray

try:  # built by `pip install`; a source tree that was never built has none
    from armfleet.controllers._fleet_kernel import ReferenceStepper
except ImportError:  # pragma: no cover - the test command always builds it
    ReferenceStepper = None

_WORKING, _FINISHED = int(ruckig.Result.Working), int(ruckig.Result.Finished)


class TrajectoryError(ArmfleetError):
    """Ruckig could not plan a motion (it reports why)."""


@dataclass(frozen=True)
class SampledMotion:
    """A reference given sample by sample, one row per period after the start.

    Attributes:
        position, velocity, acceleration: arrays (samples x joints); the last row
            is the goal, at rest.
    """

    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray

    @property
    def steps(self) -> int:
        """Number of periods it lasts."""
        return int(self.position.shape[0])


@dataclass(frozen=True)
class MotionPlan:
    """A planned motion, checked before it is followed.

    Attributes:
        duration: time to reach the target [s].
        position_min, position_max: per-joint extremes along the way.
        input: the Ruckig input that produces it.
    """

    duration: float
    position_min: FloatArray
    position_max: FloatArray
    input: Any


class JerkLimitedTrajectory:
    """A reference (position, velocity, acceleration) that Ruckig moves to targets.

    Args:
        start: initial position, at rest [rad or m].
        period: time between :meth:`advance` calls [s].
        max_velocity, max_acceleration, max_jerk: per-joint limits (units per s^k).
        buffers: arrays to keep the position, velocity and acceleration in (see :meth:`bind`).
        compiled: step with Ruckig's C++ library where it is built (see the module docstring).
    """

    def __init__(
        self,
        start: FloatArray,
        period: float,
        max_velocity: FloatArray,
        max_acceleration: FloatArray,
        max_jerk: FloatArray,
        buffers: tuple[FloatArray, FloatArray, FloatArray] | None = None,
        *,
        compiled: bool = True,
    ) -> None:
        dofs = len(start)
        self._stepper = (
            ReferenceStepper(dofs, period) if compiled and ReferenceStepper is not None else None
        )
        self._otg = ruckig.Ruckig(dofs, period)
        self._input = ruckig.InputParameter(dofs)
        self._output = ruckig.OutputParameter(dofs)
        self._input.max_velocity = list(max_velocity)
        self._input.max_acceleration = list(max_acceleration)
        self._input.max_jerk = list(max_jerk)
        self.position = np.array(start, dtype=float)
        self.velocity = np.zeros(dofs)
        self.acceleration = np.zeros(dofs)
        if buffers is not None:
            self.bind(*buffers)
        elif self._stepper is not None:
            self._stepper.bind(self.position, self.velocity, self.acceleration)
        self._moving = False
        self._samples: SampledMotion | None = None
        self._sample_index = 0

    def bind(self, position: FloatArray, velocity: FloatArray, acceleration: FloatArray) -> None:
        """Keep the reference in the given arrays from now on (e.g. views of the world's
        joint memory), with its current values."""
        position[:], velocity[:], acceleration[:] = self.position, self.velocity, self.acceleration
        self.position, self.velocity, self.acceleration = position, velocity, acceleration
        if self._stepper is not None:
            self._stepper.bind(position, velocity, acceleration)

    def on_restored(self) -> None:
        """Forget the motion Ruckig's solvers keep in compiled code (a world restored from a
        snapshot, :mod:`armfleet.world.world_snapshot`): the next motion is calculated
        afresh, as by solvers just made, whatever they followed before."""
        dofs, period = self._otg.degrees_of_freedom, self._otg.delta_time
        self._otg.reset()
        self._output = ruckig.OutputParameter(dofs)
        if self._stepper is not None:
            self._stepper = type(self._stepper)(dofs, period)
            self._stepper.bind(self.position, self.velocity, self.acceleration)

    @property
    def moving(self) -> bool:
        return self._moving

    @property
    def samples(self) -> SampledMotion | None:
        """The sampled motion being followed, or None (a Ruckig motion, or at rest)."""
        return self._samples

    @property
    def following_samples(self) -> bool:
        """Whether the reference is following a :class:`SampledMotion`."""
        return self._samples is not None

    def plan(self, target: FloatArray, minimum_duration_s: float | None = None) -> MotionPlan:
        """Plan from the current reference state to rest at ``target``, without following it.

        Args:
            target: joint positions [rad or m].
            minimum_duration_s: take at least this long [s] (every joint still
                starts and finishes together, within its limits).
        """
        candidate = self._input_from_here(self._input.max_acceleration, self._input.max_jerk)
        candidate.target_position = [float(x) for x in target]
        if minimum_duration_s is not None:
            candidate.minimum_duration = float(minimum_duration_s)
        trajectory = ruckig.Trajectory(len(self.position))
        result = calculate(self._otg, candidate, trajectory)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            raise TrajectoryError(f"Ruckig cannot plan this motion: {result}")
        extrema = trajectory.position_extrema
        return MotionPlan(
            float(trajectory.duration),
            np.array([e.min for e in extrema]),
            np.array([e.max for e in extrema]),
            candidate,
        )

    def stop(self, max_acceleration: FloatArray, max_jerk: FloatArray) -> float:
        """Bring the reference to rest as fast as the given (stopping) limits allow.

        Returns the stopping time [s].
        """
        stopping = self._input_from_here(list(max_acceleration), list(max_jerk))
        stopping.control_interface = ruckig.ControlInterface.Velocity
        trajectory = ruckig.Trajectory(len(self.position))
        result = calculate(self._otg, stopping, trajectory)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            raise TrajectoryError(f"Ruckig cannot plan a stop: {result}")
        self._take(stopping)
        return float(trajectory.duration)

    def _input_from_here(self, max_acceleration: Any, max_jerk: Any) -> Any:
        """A Ruckig input starting at the current reference state, ending at rest."""
        dofs = len(self.position)
        start = ruckig.InputParameter(dofs)
        start.max_velocity = self._input.max_velocity
        start.max_acceleration = max_acceleration
        start.max_jerk = max_jerk
        start.current_position = self.position.tolist()
        start.current_velocity = self.velocity.tolist()
        start.current_acceleration = self.acceleration.tolist()
        start.target_velocity = [0.0] * dofs
        start.target_acceleration = [0.0] * dofs
        return start

    def remaining_positions(self, period: float) -> FloatArray:
        """The reference positions (rows) at each coming ``period`` until the motion ends;
        no rows when at rest. Reads the motion without advancing it."""
        dofs = len(self.position)
        if not self._moving:
            return np.empty((0, dofs))
        if self._samples is not None:
            return np.array(self._samples.position[self._sample_index :], dtype=float)
        self._sync_input()
        trajectory = ruckig.Trajectory(dofs)
        result = calculate(self._otg, self._input, trajectory)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            return np.array([self.position], dtype=float)
        steps = max(1, int(np.ceil(trajectory.duration / period - 1e-9)))
        times = np.minimum(np.arange(1, steps + 1) * period, trajectory.duration)
        return np.array([trajectory.at_time(float(t))[0] for t in times], dtype=float)

    def follow(self, plan: MotionPlan) -> None:
        """Start following ``plan`` (made by :meth:`plan` from the current state)."""
        self._take(plan.input)

    def _take(self, motion: Any) -> None:
        """Follow the Ruckig input ``motion`` from now on."""
        self._input = motion
        self._samples = None
        self._moving = True
        if self._stepper is not None:
            self._stepper.follow(
                motion.current_position, motion.current_velocity, motion.current_acceleration,
                motion.target_position, motion.target_velocity, motion.target_acceleration,
                motion.max_velocity, motion.max_acceleration, motion.max_jerk,
                motion.control_interface == ruckig.ControlInterface.Velocity,
                motion.minimum_duration,
            )  # fmt: skip

    def _sync_input(self) -> None:
        """Bring the Python input up to the reference's state, as ``pass_to_input`` would
        have at each step (the C++ stepper advances only its own copy)."""
        if self._stepper is not None:
            self._input.current_position = self.position.tolist()
            self._input.current_velocity = self.velocity.tolist()
            self._input.current_acceleration = self.acceleration.tolist()

    def follow_samples(self, motion: SampledMotion) -> None:
        """Start following ``motion``: its first row is the reference one period from now."""
        self._samples = motion
        self._sample_index = 0
        self._moving = motion.steps > 0

    def advance(self) -> None:
        """Move the reference one period along the planned motion."""
        if not self._moving:
            return
        if self._samples is not None:
            self._advance_sample(self._samples)
            return
        if self._stepper is not None:
            result = self._stepper.step()
            if result != _WORKING and result != _FINISHED:
                self._moving = False
                raise TrajectoryError(f"Ruckig failed mid-motion: {ruckig.Result(result)}")
        else:
            result = self._otg.update(self._input, self._output)
            if result not in (ruckig.Result.Working, ruckig.Result.Finished):
                self._moving = False
                raise TrajectoryError(f"Ruckig failed mid-motion: {result}")
            output = self._output
            self.position[:] = output.new_position
            self.velocity[:] = output.new_velocity
            self.acceleration[:] = output.new_acceleration
            output.pass_to_input(self._input)
        if result == _FINISHED:
            self._moving = False
            self.velocity[:] = 0.0
            self.acceleration[:] = 0.0

    def _advance_sample(self, motion: SampledMotion) -> None:
        index = self._sample_index
        self.position[:] = motion.position[index]
        self.velocity[:] = motion.velocity[index]
        self.acceleration[:] = motion.acceleration[index]
        self._sample_index = index + 1
        if self._sample_index >= motion.steps:
            self._samples = None
            self._moving = False
            self.velocity[:] = 0.0
            self.acceleration[:] = 0.0


#: Relative cuts of the jerk limits tried when Ruckig fails on its own input.
_JERK_NUDGES = (1e-9, 1e-6, 1e-3)


def calculate(otg: Any, motion: Any, trajectory: Any) -> Any:
    """Ruckig's ``calculate``, past its numerical edge cases.

    Ruckig 0.19 raises ``RuckigError`` ("error in step 1") for a move from rest whose
    length is exactly ``2 a^3 / j^2`` (0.1 rad with armfleet's 5 rad/s^2 and 50 rad/s^3):
    a profile on the boundary between two of its cases. Such an input is planned again
    with the jerk limits lowered by a hair (at most 1e-3 of them, so still within the
    limits); ``motion`` keeps the limits that worked, and whatever follows it (the C++
    stepper included) plans the same motion.

    Raises:
        TrajectoryError: Ruckig fails with every nudge too.
    """
    limits = list(motion.max_jerk)
    for nudge in (0.0, *_JERK_NUDGES):
        motion.max_jerk = [limit * (1.0 - nudge) for limit in limits]
        try:
            return otg.calculate(motion, trajectory)
        except ruckig.RuckigError:
            continue
    motion.max_jerk = limits
    raise TrajectoryError("Ruckig cannot plan this motion (a numerical failure of Ruckig)")
