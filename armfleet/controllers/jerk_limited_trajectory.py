"""Jerk-limited joint motion with Ruckig, re-planned from the current reference state."""

from __future__ import annotations

import numpy as np
import ruckig

from armfleet.errors import ArmfleetError
from armfleet.messages import FloatArray


class TrajectoryError(ArmfleetError):
    """Ruckig could not plan a motion (it reports why)."""


class JerkLimitedTrajectory:
    """A reference (position, velocity, acceleration) that Ruckig moves to targets.

    Args:
        start: initial position, at rest [rad or m].
        period: time between :meth:`advance` calls [s].
        max_velocity, max_acceleration, max_jerk: per-joint limits (units per s^k).
    """

    def __init__(
        self,
        start: FloatArray,
        period: float,
        max_velocity: FloatArray,
        max_acceleration: FloatArray,
        max_jerk: FloatArray,
    ) -> None:
        dofs = len(start)
        self._otg = ruckig.Ruckig(dofs, period)
        self._input = ruckig.InputParameter(dofs)
        self._output = ruckig.OutputParameter(dofs)
        self._input.max_velocity = list(max_velocity)
        self._input.max_acceleration = list(max_acceleration)
        self._input.max_jerk = list(max_jerk)
        self.position = np.array(start, dtype=float)
        self.velocity = np.zeros(dofs)
        self.acceleration = np.zeros(dofs)
        self._moving = False

    @property
    def moving(self) -> bool:
        return self._moving

    def set_target(self, target: FloatArray) -> float:
        """Plan from the current reference state to rest at ``target``; return its duration [s]."""
        self._input.current_position = self.position.tolist()
        self._input.current_velocity = self.velocity.tolist()
        self._input.current_acceleration = self.acceleration.tolist()
        self._input.target_position = [float(x) for x in target]
        self._input.target_velocity = [0.0] * len(self.position)
        self._input.target_acceleration = [0.0] * len(self.position)
        self._moving = True
        trajectory = ruckig.Trajectory(len(self.position))
        result = self._otg.calculate(self._input, trajectory)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            self._moving = False
            raise TrajectoryError(f"Ruckig cannot plan this motion: {result}")
        return float(trajectory.duration)

    def advance(self) -> None:
        """Move the reference one period along the planned motion."""
        if not self._moving:
            return
        result = self._otg.update(self._input, self._output)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            self._moving = False
            raise TrajectoryError(f"Ruckig failed mid-motion: {result}")
        output = self._output
        self.position[:] = output.new_position
        self.velocity[:] = output.new_velocity
        self.acceleration[:] = output.new_acceleration
        output.pass_to_input(self._input)
        if result == ruckig.Result.Finished:
            self._moving = False
            self.velocity[:] = 0.0
            self.acceleration[:] = 0.0
