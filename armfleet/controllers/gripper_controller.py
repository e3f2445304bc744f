"""gripper_controller: a gripper's fingers or jaws, to an opening or closed with a force.

The gripper's joints are the description's (:mod:`~armfleet.controllers.gripper_joints`:
its ``gripper_joints``, else the prismatic joints off the base_link -> tool0 chain, the
Panda's two fingers). Its leaders are commanded; a mimic joint follows its leader
(``m q_leader + o``, driven by this controller at every step: PyBullet does not
enforce ``<mimic>``). The opening ``width`` is measured in the leaders' own units:

* prismatic fingers: the sum of the fingers' positions [m] (the distance between the
  pads of a parallel gripper), followers moving with their leader counted too, so a
  Panda whose second finger mimics the first measures as one with two fingers;
* revolute jaws: the sum of the leaders' angles [rad], one jaw: its angle; its force is
  a torque [N m], and its gains are the prismatic ones scaled to the jaw's moment of
  inertia (``jaw_stiffness_s2``, ``jaw_damping_s``: a jaw of any size is as stiff, for its
  inertia, as a Panda finger).

Closing drives the leaders towards their lower limits (the narrowest opening); the
widest is at their upper limits. The position_controller leaves the gripper's joints
to this controller, which runs after it and writes their efforts:

* to a width: a jerk-limited (Ruckig) reference per leader, followed by
  ``f = m a_ref + k (q_ref - q) + c (v_ref - v) + damping v``, clipped to the force limit;
* closing: the same, towards the narrowest opening. A leader that falls more than
  ``block_distance_m`` (``block_angle_rad``) behind its reference is blocked by
  something and from then on presses with the grasp force. Once all are blocked, a
  spring (the same stiffness) keeps them where they closed, as the real gripper's
  coupled fingers do. Leaders that reach their limit instead have closed on nothing;
* a follower: a spring and damper on ``q - (m q_leader + o)``, its
  reaction on the leader as through a linkage (so neither moves without the other);
  once every leader squeezes it also presses closed with the grasp force;
* revolute jaws also carry the position controller's inverse dynamics (RNEA of the
  released joints at zero acceleration: gravity and the arm's motion). Without it the
  SO-100's jaw sagged 2 mrad under gravity (its stiffness is 2.8 N m/rad).

It holds something when every moving finger (and, for a single moving jaw, the link it
closes against) touches the same body while squeezing.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from armfleet.controllers.controller import ArmContext, Controller
from armfleet.controllers.finger_motion import plan_fingers
from armfleet.controllers.gripper_joints import GripperJoints, gripper_joints
from armfleet.controllers.gripper_joints import finger_indices as finger_indices  # callers' name
from armfleet.controllers.jerk_limited_trajectory import JerkLimitedTrajectory
from armfleet.controllers.parameters import ParameterSpec
from armfleet.controllers.position_controller import PositionController, as_slice
from armfleet.errors import ArmfleetError, GripperCommandError
from armfleet.messages import FloatArray, GripperCommand, GripperMode, GripperState
from armfleet.physics.joint_memory import JointViews, Row

logger = logging.getLogger("armfleet")


class GripperController(Controller):
    """Takes :class:`GripperCommand` on ``/<arm>/gripper_controller/commands``.

    Args:
        position_controller: the arm's controller, which releases the gripper's joints
            to this one.
        joints: the gripper's joints (:func:`~armfleet.controllers.gripper_joints.gripper_joints`);
            by default the prismatic joints off the arm chain.
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
        # Revolute jaws (SO-100's): their own units, gains per unit of moment of inertia.
        ParameterSpec("max_speed_rad_s", 2.0, "speed limit of each jaw [rad/s]", 1e-3, 100.0),
        ParameterSpec("max_acceleration_rad_s2", 20.0, "acceleration limit of each jaw", 1e-3, 1e4),
        ParameterSpec("max_jerk_rad_s3", 1000.0, "jerk limit of each jaw [rad/s^3]", 1e-3, 1e7),
        ParameterSpec("jaw_stiffness_s2", 1.3e5, "jaw stiffness per inertia [1/s^2]", 0.0, 1e7),
        ParameterSpec(
            "jaw_damping_s", 800.0, "velocity feedback of a jaw per its inertia [1/s]", 0.0, 1e5
        ),
        ParameterSpec("grasp_torque_n_m", 1.0, "default grasp torque of each jaw [N m]", 1e-3, 1e4),
        ParameterSpec(
            "block_angle_rad", 0.02, "jaw lag behind the reference that means blocked", 1e-5, 1.0
        ),
        ParameterSpec(
            "min_angle_rad", 0.02, "closer than this to closed, nothing is held [rad]", 0.0, 1.0
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
        joints: GripperJoints | None = None,
    ) -> None:
        super().__init__(arm, parameter_file, overrides)
        self._position_controller = position_controller
        self._joints = joints

    def on_configure(self) -> None:
        kinematics = self.arm.kinematics
        joints = self._joints if self._joints is not None else gripper_joints(kinematics)
        self._fingers = joints.leaders
        if self._fingers.size == 0:
            raise ArmfleetError(f"{self.arm.name}: the model has no fingers for a gripper")
        #: Whether the leaders are revolute jaws (opening in [rad], force in [N m]).
        self.revolute = joints.revolute
        self._every_joint = joints.indices
        self._every_damping = kinematics.damping[self._every_joint]
        self._every_limit = kinematics.effort_limit[self._every_joint]
        self._finger_part = as_slice(self._fingers)  # faster to index with than the indices
        self.finger_names = tuple(kinematics.joint_names[i] for i in self._fingers)
        body = self.arm.body
        self._links = [body.joint_indices[i] for i in self._every_joint]
        if joints.anvil is not None:
            self._links.append(body.link_index(joints.anvil))
        for link in self._links:  # rubber pads
            body.set_friction(
                link,
                float(self.parameters["pad_friction"]),
                float(self.parameters["pad_spinning_friction_m"]),
            )
        self._lower, self._upper = self._leader_limits(joints)
        # The opening: sum(weight * leader) + constant (see the module docstring).
        weight = np.ones(self._fingers.size)
        constant = 0.0
        counted = list(self._fingers)
        if not self.revolute:
            leader_slot = {int(index): slot for slot, index in enumerate(self._fingers)}
            for follower in joints.followers:
                if follower.multiplier > 0.0:
                    weight[leader_slot[follower.leader]] += follower.multiplier
                    constant += follower.offset
                    counted.append(follower.index)
        self._width_joints = np.array(sorted(counted), dtype=int)
        self._weight, self._constant = weight, constant
        self._weight_sum = float(np.sum(weight))
        #: Widest and narrowest opening [m, or rad for revolute jaws].
        self.max_width = float(np.sum(weight * self._upper) + constant)
        self.min_width = float(np.sum(weight * self._lower) + constant)
        #: Largest force a leader can press with (its URDF effort limit) [N, or N m].
        self.max_force = float(np.min(kinematics.effort_limit[self._fingers]))
        inertia = self._moved_inertia()
        self.finger_mass = inertia[self._fingers]
        self._damping = kinematics.damping[self._fingers]
        n = self._fingers.size
        self._configure_gains(inertia, n)
        #: Per leader: the lag behind the reference that means blocked (constants, as
        #: arrays for the law: see finger_law.py).
        block = "block_angle_rad" if self.revolute else "block_distance_m"
        self.block_distance = np.full(n, float(self.parameters[block]))
        self._closed_margin = float(
            self.parameters["min_angle_rad" if self.revolute else "min_width_m"]
        )
        self.trajectory: JerkLimitedTrajectory | None = None
        # The state the law reads, per leader; in a world, views of its joint memory
        # (see bind()), where the fleet path updates every gripper at once.
        self._reference = (np.zeros(n), np.zeros(n), np.zeros(n))
        self._force = np.full(n, min(self.default_force, self.max_force))
        self._blocked = np.zeros(n, dtype=bool)
        self._grasping = np.zeros(n, dtype=bool)
        #: Columns of the world's joint memory the leaders' state is kept in, or None.
        self.memory_columns: npt.NDArray[np.int_] | None = None
        self._offset_ref = [0.0] * n
        self._mass_list: list[float] = self.finger_mass.tolist()
        self._damping_list: list[float] = self._damping.tolist()
        self._follower_law = [
            (
                f.index, f.leader, f.multiplier, f.offset, float(self._joint_stiffness[f.index]),
                float(self._joint_gain[f.index]), float(kinematics.damping[f.index]),
                float(kinematics.effort_limit[f.index]), float(kinematics.effort_limit[f.leader]),
            )
            for f in joints.followers
        ]  # fmt: skip
        self._target_width = 0.0
        self._state_topic = self.arm.topic("gripper_controller/state")
        commands = self.arm.topic("gripper_controller/commands")
        self.arm.bus.advertise(commands, GripperCommand)
        self.arm.bus.advertise(self._state_topic, GripperState)
        # on_error: a command this controller failed to take faults its arm, not skipped.
        self._subscription = self.arm.bus.subscribe(commands, self._on_command, on_error=self.fail)

    def _leader_limits(self, joints: GripperJoints) -> tuple[FloatArray, FloatArray]:
        """The leaders' position limits, narrowed so that every follower stays in its own."""
        kinematics = self.arm.kinematics
        lower = kinematics.lower[self._fingers].copy()
        upper = kinematics.upper[self._fingers].copy()
        for follower in joints.followers:
            if follower.multiplier == 0.0:
                continue
            slot = int(np.flatnonzero(self._fingers == follower.leader)[0])
            ends = (
                (kinematics.lower[follower.index] - follower.offset) / follower.multiplier,
                (kinematics.upper[follower.index] - follower.offset) / follower.multiplier,
            )
            lower[slot] = max(lower[slot], min(ends))
            upper[slot] = min(upper[slot], max(ends))
        return lower, upper

    def _moved_inertia(self) -> FloatArray:
        """Per joint (indexed like q): what a gripper joint moves, its link's mass [kg] for
        a prismatic finger, the moment of inertia about its axis of all it carries
        [kg m^2] for a revolute jaw (the joint-space inertia's diagonal at mid-range)."""
        kinematics = self.arm.kinematics
        model = kinematics.model
        mass = np.zeros(model.nq)
        for j in range(1, model.njoints):
            mass[model.joints[j].idx_q] = model.inertias[j].mass
        if self.revolute:
            data = model.createData()
            diagonal = np.diag(pin.crba(model, data, kinematics.mid_range()))
            mass[self._every_joint] = diagonal[self._every_joint]
        return mass

    def _configure_gains(self, inertia: FloatArray, n: int) -> None:
        """Per leader: trajectory limits and feedback gains, in the leaders' units."""
        kinematics = self.arm.kinematics
        if self.revolute:
            speed, acceleration, jerk = (
                "max_speed_rad_s",
                "max_acceleration_rad_s2",
                "max_jerk_rad_s3",
            )
            stiffness = inertia * float(self.parameters["jaw_stiffness_s2"])
            gain = inertia * float(self.parameters["jaw_damping_s"])
        else:
            speed, acceleration, jerk = "max_speed_m_s", "max_acceleration_m_s2", "max_jerk_m_s3"
            stiffness = np.full(inertia.size, float(self.parameters["stiffness_n_m"]))
            gain = np.full(inertia.size, float(self.parameters["damping_n_s_m"]))
        self._speed = np.minimum(kinematics.velocity_limit[self._fingers], self.parameters[speed])
        self._acceleration = np.full(n, float(self.parameters[acceleration]))
        self._jerk = np.full(n, float(self.parameters[jerk]))
        self._joint_stiffness, self._joint_gain = stiffness, gain
        #: Per leader: the feedback gains (constants, as arrays for the law).
        self.stiffness = stiffness[self._fingers]
        self.gain = gain[self._fingers]
        self._stiffness_list: list[float] = self.stiffness.tolist()
        self._gain_list: list[float] = self.gain.tolist()

    @property
    def default_force(self) -> float:
        """The grasp force [N] (of a revolute jaw: torque [N m]) when a command gives none."""
        return float(self.parameters["grasp_torque_n_m" if self.revolute else "grasp_force_n"])

    @property
    def width_unit(self) -> str:
        """The unit of the opening: ``m`` (prismatic fingers) or ``rad`` (revolute jaws)."""
        return "rad" if self.revolute else "m"

    @property
    def force_unit(self) -> str:
        """The unit of the force: ``N`` (prismatic fingers) or ``N m`` (revolute jaws)."""
        return "N m" if self.revolute else "N"

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
        self._target_width = float(np.sum(self._weight * start) + self._constant)
        self._position_controller.release(self._every_joint)

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
                self.arm.name, "force", command.force, self.force_unit, 0.0, self.max_force
            )
        if not command.grasp and not (
            math.isfinite(command.width) and self.min_width <= command.width <= self.max_width
        ):
            raise GripperCommandError(
                self.arm.name, "width", command.width, self.width_unit, self.min_width,
                self.max_width,
            )  # fmt: skip
        return command

    def command(self, command: GripperCommand) -> None:
        """Start ``command`` now (checked first; the current one is dropped)."""
        self.check(command)
        if self.trajectory is None:
            raise ArmfleetError(f"{self.arm.name}: gripper_controller is not active")
        width = self.min_width if command.grasp else command.width
        per_finger = np.clip(
            self._lower + (width - self.min_width) / self._weight_sum, self._lower, self._upper
        )
        limits = (self._speed, self._acceleration, self._jerk)
        self.trajectory.follow(plan_fingers(self.trajectory, per_finger, limits, self.period))
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
        """Measured opening: between the finger pads [m], or the jaws' angle [rad]."""
        return float(np.sum(self.arm.body.position[self._width_joints]))

    @property
    def target_width(self) -> float:
        return self._target_width

    @property
    def force(self) -> float:
        """Force the leaders press with now [N, or N m] (mean of their efforts, positive
        closing)."""
        effort: list[float] = self.arm.body.effort_command[self._finger_part].tolist()
        return -sum(effort) / len(effort)

    @property
    def mode(self) -> GripperMode:
        moving = self.trajectory is not None and self.trajectory.moving
        if not self._grasping.all():
            return GripperMode.MOVING if moving else GripperMode.AT_WIDTH
        blocked = bool(self._blocked.all())
        if self.width - self.min_width <= self._closed_margin and (blocked or not moving):
            return GripperMode.CLOSED  # on nothing, or what it held slipped out
        return GripperMode.SQUEEZING if blocked else GripperMode.CLOSING

    @property
    def holding(self) -> bool:
        """Squeezing something that every finger (and a single jaw's anvil) touches."""
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
            body.effort_command[part] = [
                -f
                if stuck
                else min(f, max(-f, m * a + k * (x - q_i) + c * (u - v_i) + d * v_i))
                for q_i, v_i, x, u, a, m, k, c, d, f, stuck in zip(
                    q, v, position, velocity, acceleration, self._mass_list,
                    self._stiffness_list, self._gain_list, self._damping_list, force, blocked,
                    strict=True,
                )
            ]  # fmt: skip
        self.complete_efforts()
        self.finish_update(stamp)

    def hold_where_closed(self, q: FloatArray) -> None:
        """Every leader is blocked at ``q``: keep them there relative to each other."""
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
        force = float(self._force[0])
        q_mean = sum(positions) / len(positions)
        v_mean = sum(velocities) / len(velocities)
        limit = self.max_force
        return [
            min(
                limit,
                max(-limit, -force + k * (ref - (q_i - q_mean)) - c * (v_i - v_mean) + d * v_i),
            )
            for q_i, v_i, ref, k, c, d in zip(
                positions, velocities, self._offset_ref, self._stiffness_list, self._gain_list,
                self._damping_list, strict=True,
            )
        ]  # fmt: skip

    @property
    def completes_efforts(self) -> bool:
        """Whether :meth:`complete_efforts` has work: followers, or revolute jaws."""
        return bool(self._follower_law) or self.revolute

    def complete_efforts(self) -> None:
        """After the leaders' efforts (in both the single and the fleet path): the
        followers', then for revolute jaws the position controller's inverse dynamics
        added (gravity and the arm's motion, which swing a jaw; a Panda finger slides
        across both), clipped to the effort limits."""
        self.drive_followers()
        if not self.revolute:
            return
        body, joints = self.arm.body, self._every_joint
        velocity = body.velocity[joints]
        carried = self._position_controller.inverse_dynamics_torque[joints]
        effort = body.effort_command[joints] + (carried - self._every_damping * velocity)
        body.effort_command[joints] = np.clip(effort, -self._every_limit, self._every_limit)

    def drive_followers(self) -> None:
        """Write each follower's effort, and its reaction on its leader.

        The coupling is a spring and damper on ``q - (m q_leader + o)``: the follower
        is pulled towards ``m q_leader + o`` at ``m v_leader`` and its leader takes the
        reaction (``-m`` times it), as through the mechanism's linkage, so neither can
        move without the other. Its gains are the finger's divided by ``1 + m^2``: the
        pair's relative motion then sees the gains a single finger sees (with the full
        gains on both sides, its damping exceeded what the 1 ms step integrates stably:
        the Panda's fingers oscillated). Once every leader squeezes, the follower also presses
        closed with the grasp force (mirrored by the multiplier's sign). Each is clipped
        to its URDF effort limit."""
        if not self._follower_law:
            return
        body = self.arm.body
        q, v, effort = body.position, body.velocity, body.effort_command
        force = float(self._force[0])
        squeezing = bool(self._blocked.all())
        for index, leader, m, o, k, c, d, limit, leader_limit in self._follower_law:
            q_i, v_i = float(q[index]), float(v[index])
            target, speed = m * float(q[leader]) + o, m * float(v[leader])
            coupling = (k * (target - q_i) + c * (speed - v_i)) / (1.0 + m * m)
            pressing = (-force if m > 0.0 else force) if squeezing else 0.0
            own = coupling + pressing + d * v_i
            effort[index] = min(limit, max(-limit, own))
            reaction = float(effort[leader]) - m * coupling
            effort[leader] = min(leader_limit, max(-leader_limit, reaction))

    def finish_update(self, stamp: float) -> None:
        """After the efforts are written: publish the state, advance the reference."""
        if self.arm.bus.has_subscribers(self._state_topic):
            self.arm.bus.publish(self._state_topic, self.gripper_state(stamp))
        assert self.trajectory is not None
        self.trajectory.advance()
