"""One arm's joint_trajectory_controller, world side: at most one trajectory at a time,
followed and judged in the stepping thread.

A new trajectory, from the action or the topic, replaces the one being followed (its
goal ends aborted, as the controller preempts it); a cancel brings the arm to rest
within its limits; a protective stop, a motion commanded by other means or the arm's
removal end the goal aborted with the reason. The ROS side
(:mod:`armfleet.ros.trajectory_action`) only hands messages over and reports.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from armfleet.errors import ArmfleetError
from armfleet.messages import FloatArray
from armfleet.ros.trajectory_goal import (
    GOAL_TOLERANCE_VIOLATED,
    INVALID_GOAL,
    PATH_TOLERANCE_VIOLATED,
    SUCCESSFUL,
    ControllerDefaults,
    GoalRefused,
    GoalResult,
    Outcome,
    PreparedTrajectory,
    prepare,
)

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm

logger = logging.getLogger("armfleet")

#: Called once with how the goal ended (stepping thread).
OnDone = Callable[[GoalResult], None]


@dataclass(frozen=True)
class TrackingSample:
    """What a goal's feedback reports: the reference and the measured state, per joint."""

    stamp: float
    desired_position: FloatArray
    desired_velocity: FloatArray
    desired_acceleration: FloatArray
    actual_position: FloatArray
    actual_velocity: FloatArray


@dataclass
class ActiveTrajectory:
    """A trajectory accepted by the controller, waiting for its start or being followed."""

    prepared: PreparedTrajectory
    on_done: OnDone | None
    motion: Any = None  # the SampledMotion the arm follows, once started
    result: GoalResult | None = field(default=None)

    @property
    def done(self) -> bool:
        return self.result is not None


class TrajectoryController:
    """The trajectory controller of ``arm`` (see the module docstring)."""

    def __init__(self, arm: Arm, defaults: ControllerDefaults | None = None) -> None:
        self._arm = arm
        self._defaults = defaults or ControllerDefaults()
        self._active: ActiveTrajectory | None = None
        self._indices = arm.kinematics.arm_indices

    @property
    def arm(self) -> Arm:
        return self._arm

    @property
    def active(self) -> ActiveTrajectory | None:
        return self._active

    def accept(
        self, trajectory: Any, now: float, goal: Any | None = None, on_done: OnDone | None = None
    ) -> ActiveTrajectory:
        """Take ``trajectory`` (and ``goal``'s tolerances), replacing the one followed.

        A refused trajectory changes nothing: the current one goes on.

        Raises:
            GoalRefused: with the controller's error code.
        """
        prepared = prepare(self._arm, trajectory, now, self._defaults, goal)
        entry = ActiveTrajectory(prepared, on_done)
        if prepared.start_s <= now:
            self._start(entry)  # raises GoalRefused: nothing replaced
        self._end_active(
            GoalResult(
                Outcome.ABORTED, INVALID_GOAL, "Current goal cancelled due to new incoming action."
            )
        )
        self._active = entry
        return entry

    def cancel(self, entry: ActiveTrajectory) -> None:
        """End ``entry`` canceled, bringing the arm to rest if it was following it."""
        if entry is not self._active or entry.done:
            return
        if entry.motion is not None and self._following(entry):
            self._arm.halt()
        self._end_active(GoalResult(Outcome.CANCELED, SUCCESSFUL, "canceled"))

    def close(self, reason: str) -> None:
        """End the trajectory followed, aborted with ``reason`` (the arm is leaving)."""
        self._end_active(GoalResult(Outcome.ABORTED, INVALID_GOAL, reason))

    def tracking(self, now: float) -> TrackingSample | None:
        """The reference and the measured state now, while a trajectory is followed."""
        entry = self._active
        if entry is None or entry.motion is None or entry.done:
            return None
        reference = self._arm.position_controller.trajectory
        assert reference is not None
        body = self._arm.body
        return TrackingSample(
            now,
            reference.position.copy(),
            reference.velocity.copy(),
            reference.acceleration.copy(),
            body.position[self._indices].copy(),
            body.velocity[self._indices].copy(),
        )

    def on_step(self, now: float) -> None:
        """Start a waiting trajectory, check the one followed, end it when it is judged."""
        entry = self._active
        if entry is None or entry.done:
            return
        if entry.motion is None:
            if now + 1e-12 < entry.prepared.start_s:
                return
            try:
                self._start(entry)
            except GoalRefused as refused:
                self._end_active(GoalResult(Outcome.ABORTED, refused.error_code, str(refused)))
                return
        result = self._judge(entry, now)
        if result is not None:
            self._end_active(result)

    # -- inside -----------------------------------------------------------------------
    def _start(self, entry: ActiveTrajectory) -> None:
        prepared = entry.prepared
        try:
            self._arm.follow_trajectory(
                prepared.times.tolist(),
                prepared.positions.tolist(),
                None if prepared.velocities is None else prepared.velocities.tolist(),
                None if prepared.accelerations is None else prepared.accelerations.tolist(),
            )
        except ArmfleetError as exc:
            raise GoalRefused(INVALID_GOAL, str(exc)) from None
        reference = self._arm.position_controller.trajectory
        assert reference is not None
        entry.motion = reference.samples

    def _following(self, entry: ActiveTrajectory) -> bool:
        reference = self._arm.position_controller.trajectory
        return reference is not None and reference.samples is entry.motion

    def _judge(self, entry: ActiveTrajectory, now: float) -> GoalResult | None:
        arm = self._arm
        controller = arm.position_controller
        name = arm.name
        if controller.stop_reason is not None:
            return GoalResult(
                Outcome.ABORTED,
                PATH_TOLERANCE_VIOLATED,
                f"{name}: protective stop: {controller.stop_reason}",
            )
        reference = controller.trajectory
        if reference is None:
            return GoalResult(Outcome.ABORTED, INVALID_GOAL, f"{name}: the controller stopped")
        tolerances = entry.prepared.tolerances
        actual = arm.body.position[self._indices]
        velocity = arm.body.velocity[self._indices]
        if reference.samples is entry.motion:
            return self._check_path(entry, reference.position, reference.velocity, actual, velocity)
        if reference.moving:  # another command took the arm over
            return GoalResult(
                Outcome.ABORTED, INVALID_GOAL, f"{name}: another command replaced the trajectory"
            )
        goal = entry.prepared.positions[-1]
        error = np.abs(goal - actual)
        speed = np.abs(velocity)
        if np.all(error <= tolerances.goal_position) and np.all(speed <= tolerances.goal_velocity):
            return GoalResult(Outcome.SUCCEEDED, SUCCESSFUL, "")
        if now > entry.prepared.end_s + tolerances.goal_time_s:
            joint = int(np.argmax(np.maximum(error - tolerances.goal_position, 0.0)))
            return GoalResult(
                Outcome.ABORTED,
                GOAL_TOLERANCE_VIOLATED,
                f"{name}: {arm.joint_names[joint]} is {error[joint]:.4g} from its goal "
                f"(tolerance {tolerances.goal_position[joint]:.4g}), moving at "
                f"{speed[joint]:.4g}, {tolerances.goal_time_s:g} s after the trajectory's end",
            )
        return None

    def _check_path(
        self,
        entry: ActiveTrajectory,
        desired: FloatArray,
        desired_velocity: FloatArray,
        actual: FloatArray,
        velocity: FloatArray,
    ) -> GoalResult | None:
        tolerances = entry.prepared.tolerances
        for label, error, limit in (
            ("position", np.abs(desired - actual), tolerances.path_position),
            ("velocity", np.abs(desired_velocity - velocity), tolerances.path_velocity),
        ):
            over = error > limit
            if np.any(over):
                joint = int(np.argmax(over))
                self._arm.halt()
                return GoalResult(
                    Outcome.ABORTED,
                    PATH_TOLERANCE_VIOLATED,
                    f"{self._arm.name}: {self._arm.joint_names[joint]} left its path: "
                    f"{label} error {error[joint]:.4g} > tolerance {limit[joint]:.4g}",
                )
        return None

    def _end_active(self, result: GoalResult) -> None:
        entry = self._active
        if entry is None or entry.done:
            return
        entry.result = result
        self._active = None
        if result.outcome is Outcome.ABORTED and result.error_code != SUCCESSFUL:
            logger.info(
                "%s: trajectory %s: %s", self._arm.name, result.outcome.value, result.error_string
            )
        if entry.on_done is not None:
            entry.on_done(result)
