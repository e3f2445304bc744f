"""gripper_controller: the fingers of a parallel gripper, to a width or closed with a force.

The fingers are the arm's prismatic joints off the base_link -> tool0 chain
(the Panda's two fingers); the opening ``width`` is the sum of their positions.
The position_controller leaves them to this controller, which runs after it
and writes their efforts:

* to a width: a jerk-limited (Ruckig) reference per finger, followed by
  ``f = m a_ref + k (q_ref - q) + c (v_ref - v) + damping v``, clipped to the force limit;
* closing: the same, towards width 0. A finger that falls more than
  ``block_distance_m`` behind its reference is blocked by something and from
  then on presses with the grasp force. Once both are blocked, a spring
  (the same stiffness) keeps the pair where it closed, as the real gripper's
  coupled fingers do. Fingers that reach their limit instead have closed on nothing.

It holds something when both fingers press on the same body.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from armfleet.controllers.controller import ArmContext, Controller
from armfleet.controllers.jerk_limited_trajectory import JerkLimitedTrajectory
from armfleet.controllers.parameters import ParameterSpec
from armfleet.controllers.position_controller import PositionController, as_slice
from armfleet.errors import ArmfleetError, GripperCommandError
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray, GripperCommand, GripperMode, GripperState
from armfleet.physics.joint_memory import JointViews, Row

logger = logging.getLogger("armfleet")

#: Pinocchio joint types of a finger (prismatic along any axis).
_PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


def finger_indices(kinematics: ArmKinematics) -> npt.NDArray[np.int_]:
    """Indices (into q) of the arm's fingers: prismatic joints off the base-tool chain."""
    model = kinematics.model
    fingers = [
        model.joints[j].idx_q
        for j in range(1, model.njoints)
        if model.joints[j].idx_q in kinematics.auxiliary_indices
        and model.joints[j].shortname() in _PRISMATIC
    ]
    return np.array(fingers, dtype=int)


class GripperController(Controller):
    """Takes :class:`GripperCommand` on ``/<arm>/gripper_controller/commands``.

    Args:
        position_controller: the arm's controller, which releases the fingers to this one.
    """

    type_name = "gripper_controller"
    rate_parameter = "update_rate_hz"
    parameter_schema = (
        ParameterSpec("update_rate_hz", 1000.0, "control rate [Hz]", 1.0, 100_000.0),
        ParameterSpec("max_speed_m_s", 0.1, "speed limit of each finger [m/s]", 1e-3, 10.0),
        ParameterSpec("max_acceleration_m_s2", 2.0, "acceleration limit of each finger", 1e-3, 1e3),
        ParameterSpec("max_jerk_m_s3", 100.0, "jerk limit of each finger [m/s^3]", 1e-3, 1e6),
        ParameterSpec("stiffness_n_m", 2000.0, "position feedback of each finger [N/m]", 0.0, 1e6),
        ParameterSpec("damping_n_s_m", 12.0, "velocity feedback of each finger [N s/m]", 0.0, 1e4),
        ParameterSpec("grasp_force_n", 20.0, "default grasp force of each finger [N]", 0.1, 1e4),
        ParameterSpec(
            "block_distance_m", 0.002, "lag behind the reference that means blocked", 1e-5, 0.1
        ),
        ParameterSpec("min_width_m", 0.002, "narrower than this, nothing is held [m]", 0.0, 0.1),
        ParameterSpec("pad_friction", 1.0, "friction coefficient of the finger pads", 0.0, 10.0),
        ParameterSpec(
            "pad_spinning_friction_m", 0.005, "torsional friction of the finger pads", 0.0, 1.0
        ),
    )
    writes_commands = True

    def __init__(
        self,
        arm: ArmContext,
        parameter_file: Path | None = None,
        overrides: Mapping[str, Any] | None = None,
        *,
        position_controller: PositionController,
    ) -> None:
        super().__init__(arm, parameter_file, overrides)
        self._position_controller = position_controller

    def on_configure(self) -> None:
        kinematics = self.arm.kinematics
        self._fingers = finger_indices(kinematics)
        if self._fingers.size == 0:
            raise ArmfleetError(f"{self.arm.name}: the model has no fingers for a gripper")
        self._finger_part = as_slice(self._fingers)  # faster to index with than the indices
        self.finger_names = tuple(kinematics.joint_names[i] for i in self._fingers)
        self._links = [self.arm.body.joint_indices[i] for i in self._fingers]
        for link in self._links:  # rubber pads
            self.arm.body.set_friction(
                link,
                float(self.parameters["pad_friction"]),
                float(self.parameters["pad_spinning_friction_m"]),
            )
        self._lower = kinematics.lower[self._fingers]
        self._upper = kinematics.upper[self._fingers]
        #: Widest opening [m].
        self.max_width = float(np.sum(self._upper))
        #: Largest force a finger can press with (its URDF effort limit) [N].
        self.max_force = float(np.min(kinematics.effort_limit[self._fingers]))
        joint_ids = [
            j
            for j in range(1, kinematics.model.njoints)
            if kinematics.model.joints[j].idx_q in self._fingers
        ]
        self.finger_mass = np.array([kinematics.model.inertias[j].mass for j in joint_ids])
        self._damping = kinematics.damping[self._fingers]
        n = self._fingers.size
        self._speed = np.minimum(
            kinematics.velocity_limit[self._fingers], self.parameters["max_speed_m_s"]
        )
        self._acceleration = np.full(n, float(self.parameters["max_acceleration_m_s2"]))
        self._jerk = np.full(n, float(self.parameters["max_jerk_m_s3"]))
        self._stiffness = float(self.parameters["stiffness_n_m"])
        self._gain_damping = float(self.parameters["damping_n_s_m"])
        #: Per finger: the feedback gains and the lag behind the reference that means
        #: blocked (constants, as arrays for the law: see finger_law.py).
        self.stiffness = np.full(n, self._stiffness)
        self.gain = np.full(n, self._gain_damping)
        self.block_distance = np.full(n, float(self.parameters["block_distance_m"]))
        self.trajectory: JerkLimitedTrajectory | None = None
        # The state the law reads, per finger; in a world, views of its joint memory
        # (see bind()), where the fleet path updates every gripper at once.
        self._reference = (np.zeros(n), np.zeros(n), np.zeros(n))
        self._force = np.full(n, min(float(self.parameters["grasp_force_n"]), self.max_force))
        self._blocked = np.zeros(n, dtype=bool)
        self._grasping = np.zeros(n, dtype=bool)
        #: Columns of the world's joint memory the fingers' state is kept in, or None.
        self.memory_columns: npt.NDArray[np.int_] | None = None
        self._offset_ref = [0.0] * n
        self._mass_list: list[float] = self.finger_mass.tolist()
        self._damping_list: list[float] = self._damping.tolist()
        self._target_width = 0.0
        self._state_topic = self.arm.topic("gripper_controller/state")
        commands = self.arm.topic("gripper_controller/commands")
        self.arm.bus.advertise(commands, GripperCommand)
        self.arm.bus.advertise(self._state_topic, GripperState)
        # on_error: a command this controller failed to take faults its arm, not skipped.
        self._subscription = self.arm.bus.subscribe(commands, self._on_command, on_error=self.fail)

    def on_cleanup(self) -> None:
        self._subscription.cancel()
        self.trajectory = None

    def on_activate(self) -> None:
        start = np.clip(self.arm.body.position[self._fingers], self._lower, self._upper)
        self.trajectory = JerkLimitedTrajectory(
            start, self.period, self._speed, self._acceleration, self._jerk, self._reference,
            compiled=self.arm.compiled,
        )  # fmt: skip
        self._blocked[:] = False
        self._grasping[:] = False
        self._target_width = float(np.sum(start))
        self._position_controller.release(self._fingers)

    def on_deactivate(self) -> None:
        self._position_controller.release(np.zeros(0, dtype=int))

    def bind(self, views: JointViews) -> None:
        """Keep the fingers' reference, force and flags in ``views`` (the arm's columns of
        the world's joint memory) from now on, with their current values. Fingers whose
        columns are not contiguous keep their own arrays (no views of them exist)."""
        part = self._finger_part
        if not isinstance(part, slice):
            return
        rows = (
            Row.FINGER_REFERENCE_POSITION,
            Row.FINGER_REFERENCE_VELOCITY,
            Row.FINGER_REFERENCE_ACCELERATION,
        )
        reference = tuple(views.row(row)[part] for row in rows)
        for view, current in zip(reference, self._reference, strict=True):
            view[:] = current
        self._reference = (reference[0], reference[1], reference[2])
        if self.trajectory is not None:
            self.trajectory.bind(*self._reference)
        force = views.row(Row.FINGER_FORCE)[part]
        blocked, grasping = views.finger_blocked[part], views.finger_grasping[part]
        force[:], blocked[:], grasping[:] = self._force, self._blocked, self._grasping
        self._force, self._blocked, self._grasping = force, blocked, grasping
        start = views.columns.start
        self.memory_columns = np.arange(part.start, part.stop) + start

    @property
    def fleet_ready(self) -> bool:
        """Whether the fleet path can update this gripper (its state is in the memory)."""
        return self.memory_columns is not None and self.trajectory is not None

    # -- commands ---------------------------------------------------------------------
    def check(self, command: GripperCommand) -> GripperCommand:
        """Return ``command`` if it is valid, else raise what a user needs to fix it."""
        if not (math.isfinite(command.force) and 0.0 < command.force <= self.max_force):
            raise GripperCommandError(
                self.arm.name, "force", command.force, "N", 0.0, self.max_force
            )
        if not command.grasp and not (
            math.isfinite(command.width) and 0.0 <= command.width <= self.max_width
        ):
            raise GripperCommandError(
                self.arm.name, "width", command.width, "m", 0.0, self.max_width
            )
        return command

    def command(self, command: GripperCommand) -> None:
        """Start ``command`` now (checked first; the current one is dropped)."""
        self.check(command)
        if self.trajectory is None:
            raise ArmfleetError(f"{self.arm.name}: gripper_controller is not active")
        width = 0.0 if command.grasp else command.width
        per_finger = np.clip(
            self._lower + (width - np.sum(self._lower)) / self._fingers.size,
            self._lower,
            self._upper,
        )
        self.trajectory.follow(self.trajectory.plan(per_finger))
        self._grasping[:] = command.grasp
        self._force[:] = command.force
        self._target_width = width
        self._blocked[:] = False

    def _on_command(self, command: GripperCommand) -> None:
        try:
            self.command(command)
        except ArmfleetError as exc:
            logger.warning("rejected gripper command: %s", exc)

    # -- state ------------------------------------------------------------------------
    @property
    def width(self) -> float:
        """Measured opening between the finger pads [m]."""
        return float(np.sum(self.arm.body.position[self._fingers]))

    @property
    def target_width(self) -> float:
        return self._target_width

    @property
    def force(self) -> float:
        """Force the fingers press with now [N] (mean of their efforts, positive closing)."""
        effort: list[float] = self.arm.body.effort_command[self._finger_part].tolist()
        return -sum(effort) / len(effort)

    @property
    def mode(self) -> GripperMode:
        moving = self.trajectory is not None and self.trajectory.moving
        if not self._grasping.all():
            return GripperMode.MOVING if moving else GripperMode.AT_WIDTH
        blocked = bool(self._blocked.all())
        if self.width <= self.parameters["min_width_m"] and (blocked or not moving):
            return GripperMode.CLOSED  # on nothing, or what it held slipped out
        return GripperMode.SQUEEZING if blocked else GripperMode.CLOSING

    @property
    def holding(self) -> bool:
        """Squeezing something that both fingers touch."""
        if self.mode is not GripperMode.SQUEEZING:
            return False
        touching = [self.arm.body.bodies_touching(link) for link in self._links]
        return bool(set.intersection(*touching))

    def gripper_state(self, stamp: float) -> GripperState:
        return GripperState(
            stamp, self.width, self._target_width, self.force, self.mode, self.holding
        )

    # -- control ----------------------------------------------------------------------
    def update(self, stamp: float) -> None:
        # Plain floats: with two fingers, numpy's per-call overhead would cost more
        # than the arithmetic (this runs at 1 kHz on every Panda). The fleet path runs
        # the same law on arrays of every gripper's fingers (finger_law.py), and gives
        # the same efforts bit for bit (tests/test_fleet_update.py).
        body = self.arm.body
        part = self._finger_part
        q = body.position[part].tolist()
        v = body.velocity[part].tolist()
        position, velocity, acceleration = (array.tolist() for array in self._reference)
        force = self._force.tolist()
        blocked = self._blocked.tolist()
        if self._grasping[0] and not all(blocked):
            lag = self.block_distance.tolist()
            blocked = [
                stuck or q_i - x > lag_i
                for stuck, q_i, x, lag_i in zip(blocked, q, position, lag, strict=True)
            ]
            self._blocked[:] = blocked
            if all(blocked):
                self.hold_where_closed(body.position[part])
        if all(blocked):
            body.effort_command[part] = self.squeeze_efforts(
                body.position[part], body.velocity[part]
            )
        else:
            k, c = self._stiffness, self._gain_damping
            body.effort_command[part] = [
                -f
                if stuck
                else min(f, max(-f, m * a + k * (x - q_i) + c * (u - v_i) + d * v_i))
                for q_i, v_i, x, u, a, m, d, f, stuck in zip(
                    q, v, position, velocity, acceleration, self._mass_list,
                    self._damping_list, force, blocked, strict=True,
                )
            ]  # fmt: skip
        self.finish_update(stamp)

    def hold_where_closed(self, q: FloatArray) -> None:
        """Both fingers are blocked at ``q``: keep them there relative to each other."""
        positions = q.tolist()
        mean = sum(positions) / len(positions)
        self._offset_ref = [q_i - mean for q_i in positions]

    def squeeze_efforts(self, q: FloatArray, v: FloatArray) -> list[float]:
        """Squeezing: each finger presses with the grasp force, and a spring keeps the pair
        where it closed: independent fingers would let the object and the fingers slide
        together along the closing axis (the real gripper's fingers are coupled).

        Plain floats: with two fingers, numpy's per-call overhead would cost more than the
        arithmetic."""
        positions, velocities = q.tolist(), v.tolist()
        k, c, force = self._stiffness, self._gain_damping, float(self._force[0])
        q_mean = sum(positions) / len(positions)
        v_mean = sum(velocities) / len(velocities)
        limit = self.max_force
        return [
            min(
                limit,
                max(-limit, -force + k * (ref - (q_i - q_mean)) - c * (v_i - v_mean) + d * v_i),
            )
            for q_i, v_i, ref, d in zip(
                positions, velocities, self._offset_ref, self._damping_list, strict=True
            )
        ]

    def finish_update(self, stamp: float) -> None:
        """After the efforts are written: publish the state, advance the reference."""
        if self.arm.bus.has_subscribers(self._state_topic):
            self.arm.bus.publish(self._state_topic, self.gripper_state(stamp))
        assert self.trajectory is not None
        self.trajectory.advance()
