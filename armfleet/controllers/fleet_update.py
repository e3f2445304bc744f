"""Every arm's controllers updated as their own managers would, fleet-wide where it pays.

An arm whose running controllers are the standard set (joint_state_broadcaster,
position_controller and, with fingers, gripper_controller), all at the physics
rate, takes the fleet path:

1. broadcasters: one copy of the state rows of the joint memory; each arm's
   message holds views of its own columns of that copy;
2. position controllers: the feedback, RNEA, damping, clipping and saturation flags
   of every arm in one call of the compiled kernel (compiled_control.py); or, as the
   reference, the feedback of every joint in one numpy pass over the joint memory
   (one world, one physics step: one half-step lead for all), RNEA per arm, then
   damping, clipping and the saturation flags in one pass; then each arm's state
   message and Ruckig step;
3. grippers: from four on, the finger law of every gripper in one pass
   (fleet_grippers.py), then each gripper's state message and reference step;
   fewer, arm by arm;
4. one finiteness check of every effort.

Every other arm (being brought up, in error, running a controller at a slower
rate) is updated by its own controller manager. Both paths do the same
floating-point operations on the same numbers, so they give the same torques
bit for bit (``tests/test_fleet_update.py``); a controller that raises, or
non-finite torques, fault only their own arm, as in :class:`ControllerManager`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from armfleet.controllers.compiled_control import CompiledControl, kernel_built
from armfleet.controllers.controller_manager import ControllerManager
from armfleet.controllers.fleet_grippers import FleetGrippers
from armfleet.controllers.gripper_controller import GripperController
from armfleet.controllers.joint_state_broadcaster import JointStateBroadcaster
from armfleet.controllers.position_controller import (
    PositionController,
    clip_torques,
    feedback_acceleration,
)
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray
from armfleet.physics.arm_body import ArmBody
from armfleet.physics.joint_memory import JointMemory, Row


class ControlledArm(Protocol):
    """An arm as the fleet update lays it out and updates it."""

    @property
    def name(self) -> str: ...
    @property
    def body(self) -> ArmBody: ...
    @property
    def kinematics(self) -> ArmKinematics: ...
    @property
    def controller_manager(self) -> ControllerManager: ...
    @property
    def position_controller(self) -> PositionController: ...
    @property
    def gripper_controller(self) -> GripperController | None: ...


#: Running controller types (in load order) that the fleet path updates.
FLEET_CONTROLLER_SETS = (
    (JointStateBroadcaster.type_name, PositionController.type_name),
    (JointStateBroadcaster.type_name, PositionController.type_name, GripperController.type_name),
)


#: From this many grippers on, one pass over all fingers costs less than one update each
#: (about 13 µs against 3-4 µs per gripper on the development machine).
GRIPPERS_IN_ONE_PASS = 4


@dataclass(frozen=True)
class _FleetArm:
    """An arm on the fleet path: its manager, controllers and columns of the memory.

    Attributes:
        dynamics: its kinematics and views of its columns of the position, velocity,
            acceleration and torque rows (RNEA's arguments and result, made once per
            lay-out: slicing the rows at every step costs as much as RNEA's call).
    """

    manager: ControllerManager
    broadcaster: JointStateBroadcaster
    controller: PositionController
    gripper: GripperController | None
    columns: slice
    dynamics: tuple[ArmKinematics, FloatArray, FloatArray, FloatArray, FloatArray]
    #: Its index in the compiled kernel, or None (numpy path).
    kernel_index: int | None


@dataclass(frozen=True)
class _Plan:
    """Who takes which path, for one set of running controllers of every arm."""

    #: The controller managers' versions it was made for.
    key: tuple[int, ...]
    fleet: tuple[_FleetArm, ...]
    others: tuple[ControllerManager, ...]
    #: Per column of the memory: whether its arm is on the fleet path.
    mask: npt.NDArray[np.bool_]
    everyone: bool
    #: The controllers' half physics step [s] (one world, one step; 0 with no fleet).
    half_step_s: float
    #: The fleet arms' grippers whose state is in the memory, updated in one pass.
    grippers: FleetGrippers | None
    #: The fleet arms with a gripper, and whether it is in that pass.
    gripper_arms: tuple[tuple[_FleetArm, bool], ...]
    #: Kernel indices of every fleet arm, when the kernel has them all (else None).
    kernel_indices: npt.NDArray[np.int64] | None


class FleetUpdate:
    """The controller updates of a world's arms, one step at a time.

    Args:
        memory: the world's joint memory.
        compiled: use the compiled kernel where it is built and knows the arm.
    """

    def __init__(self, memory: JointMemory, *, compiled: bool = True) -> None:
        self._memory = memory
        self._compiled = compiled and kernel_built()
        self._kernel: CompiledControl | None = None
        self._kernel_index: dict[str, int | None] = {}
        self._arms: list[ControlledArm] = []
        #: The arms' controller managers, read once per lay-out (not per step).
        self._managers: tuple[ControllerManager, ...] = ()
        self._plan: _Plan | None = None

    def lay_out(self, arms: Iterable[ControlledArm]) -> None:
        """Give ``arms`` (every arm of the world, in order) their columns of the memory."""
        self._arms = list(arms)
        memory = self._memory
        views = memory.lay_out([len(arm.body.joint_indices) for arm in self._arms])
        for arm, view in zip(self._arms, views, strict=True):
            arm.body.bind(
                view.row(Row.POSITION), view.row(Row.VELOCITY), view.row(Row.EFFORT_COMMAND)
            )
            arm.position_controller.bind(view)
            if arm.gripper_controller is not None:
                arm.gripper_controller.bind(view)
        memory.attach([arm.body for arm in self._arms], views)
        self._managers = tuple(arm.controller_manager for arm in self._arms)
        self._plan = None
        if self._compiled:
            self._kernel = CompiledControl(
                memory,
                [
                    (arm.kinematics, view.columns.start)
                    for arm, view in zip(self._arms, views, strict=True)
                ],
            )
            self._kernel_index = {
                arm.name: index for arm, index in zip(self._arms, self._kernel.indices, strict=True)
            }

    def update(self, stamp: float, step_index: int) -> None:
        """Update every arm's running controllers that are due at ``step_index``."""
        plan = self._current_plan()
        if plan.fleet:
            self._update_fleet(plan, stamp)
        for manager in plan.others:
            manager.update(stamp, step_index)

    def _current_plan(self) -> _Plan:
        key = tuple(manager.version for manager in self._managers)
        if self._plan is None or self._plan.key != key:
            self._plan = self._make_plan(key)
        return self._plan

    def _make_plan(self, key: tuple[int, ...]) -> _Plan:
        fleet: list[_FleetArm] = []
        others: list[ControllerManager] = []
        mask = np.zeros(self._memory.size, dtype=bool)
        for arm in self._arms:
            entry = _fleet_arm(arm, self._memory, self._kernel_index.get(arm.name))
            if entry is None:
                others.append(arm.controller_manager)
            else:
                fleet.append(entry)
                mask[entry.columns] = True
        half_step_s = fleet[0].controller.half_step_s if fleet else 0.0
        ready = [
            arm.gripper for arm in fleet if arm.gripper is not None and arm.gripper.fleet_ready
        ]
        together = len(ready) >= GRIPPERS_IN_ONE_PASS
        grippers = FleetGrippers(self._memory, ready) if together else None
        indices = [arm.kernel_index for arm in fleet]
        kernel_indices = (
            np.array(indices, dtype=np.int64)
            if fleet and all(index is not None for index in indices)
            else None
        )
        in_pass = set(map(id, grippers.grippers)) if grippers is not None else set()
        gripper_arms = tuple(
            (arm, id(arm.gripper) in in_pass) for arm in fleet if arm.gripper is not None
        )
        return _Plan(
            key, tuple(fleet), tuple(others), mask, bool(mask.all()), half_step_s, grippers,
            gripper_arms, kernel_indices,
        )  # fmt: skip

    def _update_fleet(self, plan: _Plan, stamp: float) -> None:
        memory = self._memory
        effort = memory.rows[Row.EFFORT_COMMAND]
        failed: list[tuple[_FleetArm, Exception]] = []
        # 1. Broadcasters: the state and efforts as they are before this update.
        sample = memory.block[Row.POSITION : Row.EFFORT_COMMAND + 1].copy()
        alive: list[_FleetArm] = []
        for arm in plan.fleet:
            columns = arm.columns
            try:
                arm.broadcaster.publish(
                    stamp, sample[0, columns], sample[1, columns], sample[2, columns]
                )
            except Exception as exc:  # contain it to this arm
                arm.manager.fail_controller(arm.broadcaster, exc)
            else:
                alive.append(arm)
        # 2. Position controllers.
        kernel = self._kernel
        if kernel is not None and plan.kernel_indices is not None and len(alive) == len(plan.fleet):
            kernel.control(plan.kernel_indices, plan.half_step_s)
            memory.saturation_steps += memory.saturated
            torqued: list[_FleetArm] = alive
        else:
            torqued = self._numpy_control(plan, alive, failed)
        moving: list[_FleetArm] = []
        for arm in torqued:
            try:
                arm.controller.advance(stamp)
            except Exception as error:
                failed.append((arm, error))
            else:
                moving.append(arm)
        for arm, cause in failed:  # after the torques: a fault zeroes the arm's efforts
            arm.manager.fail_controller(arm.controller, cause)
        # 3. Grippers.
        self._update_grippers(plan, moving, stamp)
        # 4. Finite efforts (a dot product is NaN or inf whenever an element is).
        if not math.isfinite(effort.dot(effort)):
            for arm in plan.fleet:
                arm.manager.check_efforts()

    def _numpy_control(
        self, plan: _Plan, alive: list[_FleetArm], failed: list[tuple[_FleetArm, Exception]]
    ) -> list[_FleetArm]:
        """The control law of ``alive`` in numpy and Pinocchio's bindings (the reference);
        returns the arms whose torques were written (an RNEA that raised goes in ``failed``)."""
        rows = self._memory.rows
        acceleration = rows[Row.ACCELERATION]
        feedback_acceleration(
            rows[Row.POSITION], rows[Row.VELOCITY], rows[Row.REFERENCE_POSITION],
            rows[Row.REFERENCE_VELOCITY], rows[Row.REFERENCE_ACCELERATION], rows[Row.KP],
            rows[Row.KD], half_step_s=plan.half_step_s, out=acceleration,
            scratch=rows[Row.SCRATCH],
        )  # fmt: skip
        torqued: list[_FleetArm] = []
        for arm in alive:
            kinematics, q_arm, v_arm, acceleration_arm, torque_arm = arm.dynamics
            try:
                torque_arm[:] = kinematics.rnea(q_arm, v_arm, acceleration_arm)
            except Exception as error:  # its torques are not written; faulted below
                failed.append((arm, error))
            else:
                torqued.append(arm)
        self._write_torques(plan, torqued)
        return torqued

    def _update_grippers(self, plan: _Plan, moving: list[_FleetArm], stamp: float) -> None:
        """Every moving arm's gripper: in one pass when all arms moved on, else one by one."""
        together = plan.grippers
        if together is not None and len(moving) == len(plan.fleet):
            try:
                together.write_efforts()
            except Exception:  # can't tell whose: each on its own, as its manager would
                pass
            else:
                for arm, in_pass in plan.gripper_arms:
                    self._update_gripper(arm, stamp, finish_only=in_pass)
                return
        for arm in moving:
            self._update_gripper(arm, stamp, finish_only=False)

    @staticmethod
    def _update_gripper(arm: _FleetArm, stamp: float, *, finish_only: bool) -> None:
        """``arm``'s gripper update (or only its end, after the one pass), contained."""
        gripper = arm.gripper
        if gripper is None:
            return
        try:
            if finish_only:
                gripper.finish_update(stamp)
            else:
                gripper.update(stamp)
        except Exception as exc:
            arm.manager.fail_controller(gripper, exc)

    def _write_torques(self, plan: _Plan, arms: list[_FleetArm]) -> None:
        """Damping, clipping and saturation count of ``arms`` (their RNEA torques are in)."""
        memory = self._memory
        rows = memory.rows
        effort = rows[Row.EFFORT_COMMAND]
        everyone = plan.everyone and len(arms) == len(plan.fleet)
        clipped = effort if everyone else rows[Row.CLIPPED_TORQUE]
        clip_torques(
            rows[Row.TORQUE], rows[Row.VELOCITY], rows[Row.DAMPING], rows[Row.EFFORT_LIMIT],
            rows[Row.NEGATIVE_EFFORT_LIMIT], out=clipped, scratch=rows[Row.SCRATCH],
            saturated=memory.saturated,
        )  # fmt: skip
        if not everyone:
            mask = plan.mask
            if len(arms) != len(plan.fleet):
                mask = np.zeros_like(mask)
                for arm in arms:
                    mask[arm.columns] = True
            np.copyto(effort, clipped, where=mask)
            np.logical_and(memory.saturated, mask, out=memory.saturated)
        memory.saturation_steps += memory.saturated


def _fleet_arm(
    arm: ControlledArm, memory: JointMemory, kernel_index: int | None
) -> _FleetArm | None:
    """``arm`` as a fleet-path arm, or None if its own manager must update it."""
    manager, controller = arm.controller_manager, arm.position_controller
    running = manager.running
    if (
        manager.fault is not None
        or tuple(c.type_name for c in running) not in FLEET_CONTROLLER_SETS
        or any(c.period_steps != 1 for c in running)
        or not controller.reference_in_memory
        or controller.memory_columns is None
    ):
        return None
    gripper = running[2] if len(running) == 3 else None
    assert isinstance(running[0], JointStateBroadcaster)
    assert gripper is None or isinstance(gripper, GripperController)
    columns = controller.memory_columns
    kinematics = arm.kinematics
    rows = memory.rows
    dynamics = (
        kinematics,
        rows[Row.POSITION][columns],
        rows[Row.VELOCITY][columns],
        rows[Row.ACCELERATION][columns],
        rows[Row.TORQUE][columns],
    )
    return _FleetArm(manager, running[0], controller, gripper, columns, dynamics, kernel_index)
