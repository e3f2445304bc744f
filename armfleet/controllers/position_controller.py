"""position_controller: jerk-limited motion to target joint positions, in torque mode.

Each update pairs the Ruckig reference for time t with the state measured at
t, and computes

    tau = RNEA(q, v, qdd_ref + kp (q_ref - q) + kd (v_ref - (h/2) qdd_ref - v)) + damping * v

clipped to the URDF effort limits, where h is the physics step. Joints off the
base_link -> tool0 chain (fingers) are held where they were when the controller
was activated.

The (h/2) qdd_ref is the physics engine's integrator, not a tuning term. PyBullet
steps with semi-implicit Euler, v' = v + h a then q' = q + h v', so a state that
stays on the reference's positions moves by q_ref(t + h) - q_ref(t) = h v' at each
step: its velocity at t is the backward difference (q_ref(t) - q_ref(t - h)) / h =
v_ref - (h/2) qdd_ref + O(h^2), not v_ref. Compared with v_ref, the kd term pulled
the arm off the reference by kd h qdd_ref / (2 kp) (1.0e-4 rad at 5 rad/s^2 with the
default gains); compared with the velocity the integrator gives, it does not. The
same holds when the controller runs slower than the physics (h stays the physics
step). The feed-forward qdd_ref is already what lands the state on the reference
one step later: (q_ref(t + h) - 2 q_ref(t) + q_ref(t - h)) / h^2 equals it exactly
on Ruckig's constant-jerk segments.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from armfleet.checks.real_numbers import all_real
from armfleet.controllers.controller import Controller
from armfleet.controllers.jerk_limited_trajectory import (
    JerkLimitedTrajectory,
    MotionPlan,
    SampledMotion,
)
from armfleet.controllers.parameters import ParameterSpec
from armfleet.errors import (
    ArmfleetError,
    JointLimitError,
    MotionLimitError,
    NonFiniteTarget,
    ProtectiveStopError,
    TargetLengthError,
    TargetTypeError,
)
from armfleet.messages import (
    ControllerState,
    FloatArray,
    JointCommand,
    PlannedMotion,
    Positions,
)
from armfleet.physics.joint_memory import JointViews, Row

logger = logging.getLogger("armfleet")

#: Ruckig's extrema may exceed a target at a limit by rounding; that is not an overshoot.
LIMIT_TOLERANCE_RAD = 1e-9


class PositionController(Controller):
    """Takes target joint positions on ``/<arm>/position_controller/commands``."""

    type_name = "position_controller"
    rate_parameter = "update_rate_hz"
    parameter_schema = (
        ParameterSpec("update_rate_hz", 1000.0, "control rate [Hz]", 1.0, 100_000.0),
        ParameterSpec("velocity_scaling", 0.95, "fraction of the URDF velocity limit", 0.01, 1.0),
        ParameterSpec("max_acceleration_rad_s2", 5.0, "acceleration limit [rad/s^2]", 1e-3, 1e4),
        ParameterSpec("max_jerk_rad_s3", 50.0, "jerk limit [rad/s^3]", 1e-3, 1e6),
        ParameterSpec("kp_s2", 2500.0, "position feedback gain [1/s^2]", 0.0, 1e6),
        ParameterSpec("kd_s", 100.0, "velocity feedback gain [1/s]", 0.0, 1e4),
        ParameterSpec("hold_tolerance_rad", 1e-3, "holding tolerance [rad]", 1e-9, 1.0),
        ParameterSpec(
            "protective_stop", True, "stop and hold on an unexpected contact until reset_stop()"
        ),
        ParameterSpec(
            "stop_acceleration_rad_s2", 15.0, "deceleration limit of a protective stop", 1e-3, 1e4
        ),
        ParameterSpec("stop_jerk_rad_s3", 1500.0, "jerk limit of a protective stop", 1e-3, 1e6),
    )
    writes_commands = True

    def on_configure(self) -> None:
        kinematics = self.arm.kinematics
        self._arm = kinematics.arm_indices
        self._aux = kinematics.auxiliary_indices
        self.joint_names = tuple(kinematics.joint_names[i] for i in self._arm)
        self.lower = kinematics.lower[self._arm]
        self.upper = kinematics.upper[self._arm]
        self.max_velocity = (
            kinematics.velocity_limit[self._arm] * self.parameters["velocity_scaling"]
        )
        #: Per movable joint, the updates whose torque was clipped to the effort limit.
        self.saturation_steps = np.zeros(len(kinematics.joint_names), dtype=np.int64)
        #: Why the arm is in protective stop, or None.
        self.stop_reason: str | None = None
        self._anchor_when_stopped = False
        size = len(kinematics.joint_names)
        # Full-size (every movable joint) arrays, reused at every update: the arm
        # joints' reference comes from Ruckig, the others hold where they were. In a
        # world they are views of its joint memory (see bind()).
        self._arm_part = as_slice(self._arm)
        self._ref_position = np.zeros(size)
        self._ref_velocity = np.zeros(size)
        self._ref_acceleration = np.zeros(size)
        self._kp = np.full(size, float(self.parameters["kp_s2"]))
        self._kd = np.full(size, float(self.parameters["kd_s"]))
        #: Half the physics step [s]: the velocity the integrator gives a state on the
        #: reference lags v_ref by this times qdd_ref (see the module docstring).
        self.half_step_s = 0.5 * self.arm.dt
        self._damping = kinematics.damping.copy()
        self._effort_limit = kinematics.effort_limit.copy()
        self._negative_effort_limit = -self._effort_limit
        self._acceleration = np.zeros(size)
        self._torque = np.zeros(size)
        self._scratch = np.zeros(size)
        self._saturated = np.zeros(size, dtype=bool)
        #: Joints another controller drives (the gripper's fingers): no feedback here.
        self._released = np.zeros(0, dtype=int)
        #: Columns of the world's joint memory this controller's arrays are views of.
        self.memory_columns: slice | None = None
        self.trajectory: JerkLimitedTrajectory | None = None
        self._state_topic = self.arm.topic("position_controller/state")
        self.arm.bus.advertise(self.arm.topic("position_controller/commands"), JointCommand)
        self.arm.bus.advertise(self._state_topic, ControllerState)
        # Collision-free plans announce their path here as they start (armfleet.planning).
        self.arm.bus.advertise(self.arm.topic("planned_motion"), PlannedMotion)
        # on_error: a command this controller failed to take faults its arm, not skipped.
        self._subscription = self.arm.bus.subscribe(
            self.arm.topic("position_controller/commands"), self._on_command, on_error=self.fail
        )

    def on_cleanup(self) -> None:
        self._subscription.cancel()
        self.trajectory = None

    def on_activate(self) -> None:
        body = self.arm.body
        body.read()
        n = len(self._arm)
        self._ref_position[:] = body.position
        self.trajectory = JerkLimitedTrajectory(
            body.position[self._arm],
            self.period,
            self.max_velocity,
            np.full(n, self.parameters["max_acceleration_rad_s2"]),
            np.full(n, self.parameters["max_jerk_rad_s3"]),
            buffers=self._reference_parts(),
            compiled=self.arm.compiled,
        )
        self._ref_velocity[:] = 0.0
        self._ref_acceleration[:] = 0.0
        body.release_brakes()

    def on_deactivate(self) -> None:
        self.arm.body.engage_brakes()

    def release(self, indices: npt.NDArray[np.int_]) -> None:
        """Leave the auxiliary joints ``indices`` (into q) to another controller.

        Their reference acceleration is zero in the inverse dynamics (they are
        not pulled back to where they were held) and their efforts are the other
        controller's to write, after this one's update.
        """
        if np.intersect1d(indices, self._arm).size:
            raise ArmfleetError(f"{self.arm.name}: position_controller keeps the arm joints")
        self._released = np.asarray(indices, dtype=int)
        # Released joints: no feedback gain and no reference acceleration, so their
        # commanded acceleration is zero.
        self._kp[:] = self.parameters["kp_s2"]
        self._kd[:] = self.parameters["kd_s"]
        self._kp[self._released] = 0.0
        self._kd[self._released] = 0.0
        self._ref_acceleration[self._released] = 0.0

    def bind(self, views: JointViews) -> None:
        """Keep the reference, gains and limits in ``views`` (the arm's columns of the
        world's joint memory) from now on, with their current values."""
        arrays = (
            (Row.REFERENCE_POSITION, "_ref_position"),
            (Row.REFERENCE_VELOCITY, "_ref_velocity"),
            (Row.REFERENCE_ACCELERATION, "_ref_acceleration"),
            (Row.KP, "_kp"),
            (Row.KD, "_kd"),
            (Row.DAMPING, "_damping"),
            (Row.EFFORT_LIMIT, "_effort_limit"),
            (Row.NEGATIVE_EFFORT_LIMIT, "_negative_effort_limit"),
            (Row.ACCELERATION, "_acceleration"),
            (Row.TORQUE, "_torque"),
            (Row.SCRATCH, "_scratch"),
        )
        for row, attribute in arrays:
            view = views.row(row)
            view[:] = getattr(self, attribute)
            setattr(self, attribute, view)
        views.saturation_steps[:] = self.saturation_steps
        self.saturation_steps = views.saturation_steps
        parts = self._reference_parts()
        if self.trajectory is not None and parts is not None:
            self.trajectory.bind(*parts)
        self.memory_columns = views.columns

    @property
    def reference_in_memory(self) -> bool:
        """Whether the reference lives in the world's joint memory, the Ruckig part
        included (views, so a fleet-wide update sees it without a copy)."""
        return self.memory_columns is not None and isinstance(self._arm_part, slice)

    def _reference_parts(self) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """The arm joints' part of the reference arrays, when it is a view (a slice)."""
        part = self._arm_part
        if not isinstance(part, slice):
            return None
        return self._ref_position[part], self._ref_velocity[part], self._ref_acceleration[part]

    @property
    def inverse_dynamics_torque(self) -> FloatArray:
        """Every movable joint's RNEA torque plus its damping torque at the last update,
        before clipping [N m or N] (a released joint's: what holds it still against gravity
        and the arm's motion); a read-only view."""
        view = self._torque.view()
        view.flags.writeable = False
        return view

    @property
    def held_positions(self) -> FloatArray:
        """Where the joints off the base-tool chain (fingers) are held [rad or m]."""
        held: FloatArray = self._ref_position[self._aux].copy()
        return held

    @property
    def is_moving(self) -> bool:
        return self.trajectory is not None and self.trajectory.moving

    @property
    def tracking_error(self) -> float:
        """Largest |q_ref - q| over the arm joints [rad or m]."""
        if self.trajectory is None:
            return math.inf
        q = self.arm.body.position[self._arm]
        return float(np.max(np.abs(self.trajectory.position - q)))

    @property
    def is_holding(self) -> bool:
        return not self.is_moving and self.tracking_error < self.parameters["hold_tolerance_rad"]

    def validate(self, target: Positions) -> FloatArray:
        """Return ``target`` as an array, or raise the error a user needs to fix it."""
        return check_target(self.arm.name, target, self.joint_names, self.lower, self.upper)

    def set_target(self, target: Positions) -> float:
        """Plan a motion to ``target`` and follow it; returns its duration [s]."""
        plan = self.plan(target)
        assert self.trajectory is not None  # plan() checked it
        self.trajectory.follow(plan)
        return plan.duration

    def follow(self, plan: MotionPlan) -> None:
        """Follow ``plan``, made by :meth:`plan` from the current reference (not yet advanced)."""
        if self.stop_reason is not None:
            raise ProtectiveStopError(self.arm.name, self.stop_reason)
        assert self.trajectory is not None  # plan() checked it
        self.trajectory.follow(plan)

    def follow_samples(self, motion: SampledMotion) -> None:
        """Follow a sampled reference (one row per period), checked against the limits.

        Raises:
            ProtectiveStopError, ArmfleetError: not followed; the current motion goes on.
        """
        self.check_samples(motion)
        assert self.trajectory is not None  # check_samples() checked it
        self.trajectory.follow_samples(motion)

    def check_samples(self, motion: SampledMotion) -> None:
        """Raise the error :meth:`follow_samples` would raise for ``motion``, if any."""
        if self.trajectory is None:
            raise ArmfleetError(f"{self.arm.name}: position_controller is not active")
        if self.stop_reason is not None:
            raise ProtectiveStopError(self.arm.name, self.stop_reason)
        slack = 1.0 + 1e-9
        if (
            np.any(motion.position < self.lower - LIMIT_TOLERANCE_RAD)
            or np.any(motion.position > self.upper + LIMIT_TOLERANCE_RAD)
            or np.any(np.abs(motion.velocity) > self.max_velocity * slack)
            or np.any(
                np.abs(motion.acceleration) > self.parameters["max_acceleration_rad_s2"] * slack
            )
        ):
            raise ArmfleetError(
                f"{self.arm.name}: the sampled motion leaves the joint position, velocity or "
                "acceleration limits"
            )

    @property
    def protective_stop_enabled(self) -> bool:
        return bool(self.parameters["protective_stop"])

    def protective_stop(self, reason: str) -> bool:
        """Stop within the jerk limits and hold; refuse motions until :meth:`reset_stop`.

        Returns whether this started a stop (False if disabled or already stopped).
        """
        if not self.protective_stop_enabled or self.stop_reason is not None:
            return False
        if self.trajectory is None:
            return False
        self.stop_reason = reason
        # Brake from where the arm is, not from where the reference wanted it: an
        # arm blocked by a contact then stops at once instead of pushing on.
        trajectory = self.trajectory
        # (An impact can spin a joint past its limit: brake from the limit then.)
        trajectory.position[:] = self.arm.body.position[self._arm]
        np.clip(
            self.arm.body.velocity[self._arm],
            -self.max_velocity,
            self.max_velocity,
            out=trajectory.velocity,
        )
        n = len(self._arm)
        trajectory.stop(
            np.full(n, self.parameters["stop_acceleration_rad_s2"]),
            np.full(n, self.parameters["stop_jerk_rad_s3"]),
        )
        self._anchor_when_stopped = True
        logger.warning("%s: protective stop: %s", self.arm.name, reason)
        return True

    def halt(self) -> float:
        """Bring the reference to rest within the normal acceleration and jerk limits, and
        hold there. Returns the stopping time [s] (0 when already at rest)."""
        trajectory = self.trajectory
        if trajectory is None:
            raise ArmfleetError(f"{self.arm.name}: position_controller is not active")
        if not trajectory.moving:
            return 0.0
        n = len(self._arm)
        return trajectory.stop(
            np.full(n, self.parameters["max_acceleration_rad_s2"]),
            np.full(n, self.parameters["max_jerk_rad_s3"]),
        )

    def reset_stop(self) -> None:
        """Accept motions again after a protective stop."""
        self.stop_reason = None

    def plan(self, target: Positions, minimum_duration_s: float | None = None) -> MotionPlan:
        """Plan a motion to ``target`` from the current reference, checked, not followed.

        A target sent mid-motion is planned from the moving reference; if the
        way there would overshoot a joint limit (the arm cannot stop in time),
        it is refused and the current motion goes on.

        Raises:
            TargetLengthError, NonFiniteTarget, JointLimitError, MotionLimitError.
        """
        values = self.validate(target)
        if self.trajectory is None:
            raise ArmfleetError(f"{self.arm.name}: position_controller is not active")
        if self.stop_reason is not None:
            raise ProtectiveStopError(self.arm.name, self.stop_reason)
        start = self.trajectory.position.copy()
        plan = self.trajectory.plan(values, minimum_duration_s)
        # A joint pushed a hair past its limit (an impact, the limit's own give) may
        # always move back: only going further out than where it starts is refused.
        for name, low, high, lower, upper, here in zip(
            self.joint_names,
            plan.position_min,
            plan.position_max,
            self.lower,
            self.upper,
            start,
            strict=True,
        ):
            floor, ceiling = min(lower, here), max(upper, here)
            if low < floor - LIMIT_TOLERANCE_RAD or high > ceiling + LIMIT_TOLERANCE_RAD:
                raise MotionLimitError(
                    self.arm.name, name, float(low if low < lower else high), lower, upper
                )
        return plan

    def _on_command(self, command: JointCommand) -> None:
        try:
            self.set_target(command.positions)
        except ArmfleetError as exc:
            logger.warning("rejected command: %s", exc)

    def update(self, stamp: float) -> None:
        body = self.arm.body
        q, v = body.position, body.velocity
        trajectory = self.trajectory
        assert trajectory is not None  # set by on_activate
        part = self._arm_part
        if not isinstance(part, slice):  # else the trajectory's arrays are views of these
            self._ref_position[part] = trajectory.position
            self._ref_velocity[part] = trajectory.velocity
            self._ref_acceleration[part] = trajectory.acceleration
        # qdd = qdd_ref + kp (q_ref - q) + kd (v_ref - (h/2) qdd_ref - v), in place, then
        # the torques (the same operations as the fleet-wide path, see FleetUpdate).
        feedback_acceleration(
            q, v, self._ref_position, self._ref_velocity, self._ref_acceleration,
            self._kp, self._kd, half_step_s=self.half_step_s, out=self._acceleration,
            scratch=self._scratch,
        )  # fmt: skip
        self._torque[:] = self.arm.kinematics.rnea(q, v, self._acceleration)
        clip_torques(
            self._torque, v, self._damping, self._effort_limit, self._negative_effort_limit,
            out=body.effort_command, scratch=self._scratch, saturated=self._saturated,
        )  # fmt: skip
        self.saturation_steps += self._saturated
        self.advance(stamp)

    def advance(self, stamp: float) -> None:
        """Publish the state (reference and measured at ``stamp``) and move the reference
        one period on; the last part of :meth:`update` once the torques are written."""
        trajectory = self.trajectory
        assert trajectory is not None  # set by on_activate
        body, part = self.arm.body, self._arm_part
        if self.arm.bus.has_subscribers(self._state_topic):
            self.arm.bus.publish(
                self._state_topic,
                ControllerState(
                    stamp,
                    self.joint_names,
                    trajectory.position.copy(),
                    trajectory.velocity.copy(),
                    trajectory.acceleration.copy(),
                    body.position[part].copy(),
                    body.velocity[part].copy(),
                    trajectory.moving,
                ),
            )
        trajectory.advance()
        if self._anchor_when_stopped and not trajectory.moving:
            # Stopped: hold where the arm is (a contact may have blocked it short of
            # the reference), so it does not keep pushing against what it touched.
            np.clip(body.position[part], self.lower, self.upper, out=trajectory.position)
            self._anchor_when_stopped = False


def feedback_acceleration(
    q: FloatArray,
    v: FloatArray,
    q_ref: FloatArray,
    v_ref: FloatArray,
    a_ref: FloatArray,
    kp: FloatArray,
    kd: FloatArray,
    *,
    half_step_s: float,
    out: FloatArray,
    scratch: FloatArray,
) -> None:
    """``out = (q_ref - q) kp + (v_ref - half_step_s a_ref - v) kd + a_ref``, in place (per
    arm or fleet-wide); ``half_step_s`` is half the physics step [s]."""
    np.subtract(q_ref, q, out=out)
    out *= kp
    np.multiply(a_ref, half_step_s, out=scratch)
    np.subtract(v_ref, scratch, out=scratch)
    scratch -= v
    scratch *= kd
    out += scratch
    out += a_ref


def clip_torques(
    torque: FloatArray,
    v: FloatArray,
    damping: FloatArray,
    limit: FloatArray,
    negative_limit: FloatArray,
    *,
    out: FloatArray,
    scratch: FloatArray,
    saturated: npt.NDArray[np.bool_],
) -> None:
    """``out = clip(torque + damping v, +-limit)``; ``saturated`` marks the clipped joints.

    ``torque`` (RNEA's) is changed in place.
    """
    np.multiply(damping, v, out=scratch)
    torque += scratch
    np.abs(torque, out=scratch)
    np.greater(scratch, limit, out=saturated)
    np.minimum(torque, limit, out=out)
    np.maximum(out, negative_limit, out=out)


def as_slice(indices: npt.NDArray[np.int_]) -> slice | npt.NDArray[np.int_]:
    """``indices`` as a slice when they are consecutive (faster to index with), else as is."""
    if indices.size and np.array_equal(indices, np.arange(indices[0], indices[0] + indices.size)):
        return slice(int(indices[0]), int(indices[0]) + indices.size)
    return indices


def check_target(
    arm: str,
    target: Positions,
    joint_names: Sequence[str],
    lower: FloatArray,
    upper: FloatArray,
) -> FloatArray:
    """Return ``target`` as an array if it has one finite in-limit value per joint.

    Raises:
        TargetLengthError, NonFiniteTarget, JointLimitError.
    """
    # A list of plain floats (the commands the arms send themselves) is real as it is.
    plain = type(target) is list and all(type(value) is float for value in target)
    if not plain and not all_real(target):  # not text, bool, complex or None (float() takes)
        raise TargetTypeError(arm, joint_names)
    try:
        values = np.asarray(target, dtype=float).reshape(-1)
    except ValueError:  # ragged
        raise TargetTypeError(arm, joint_names) from None
    if values.size != len(joint_names):
        raise TargetLengthError(arm, values.size, joint_names)
    for name, value, low, high in zip(joint_names, values, lower, upper, strict=True):
        if not math.isfinite(value):
            raise NonFiniteTarget(arm, name, float(value))
        if not low <= value <= high:
            raise JointLimitError(arm, name, float(value), float(low), float(high))
    return values
