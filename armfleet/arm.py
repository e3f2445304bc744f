"""The handle users hold for one arm of a world."""

from __future__ import annotations

from armfleet.arm_body import ArmBody
from armfleet.bus import Bus
from armfleet.controllers import ControllerManager, JointStateBroadcaster, PositionController
from armfleet.controllers.gripper_controller import GripperController
from armfleet.description import ArmDescription
from armfleet.errors import ArmFault, NoGripper
from armfleet.gripper import Gripper
from armfleet.kinematics import ArmKinematics
from armfleet.messages import (
    ArmMode,
    ArmStatus,
    FloatArray,
    JointCommand,
    JointState,
    Positions,
)
from armfleet.robot_state_publisher import RobotStatePublisher
from armfleet.safety_supervisor import SafetySupervisor
from armfleet.spawn_pose import SpawnPose


class Arm:
    """One arm: its body, model, controllers and namespace ``/<name>``.

    Created by :meth:`armfleet.World.spawn`; not meant to be built by hand.
    """

    def __init__(
        self,
        name: str,
        pose: SpawnPose,
        description: ArmDescription,
        body: ArmBody,
        kinematics: ArmKinematics,
        bus: Bus,
        controller_manager: ControllerManager,
        broadcaster: JointStateBroadcaster,
        position_controller: PositionController,
        state_publisher: RobotStatePublisher,
        safety: SafetySupervisor,
        gripper_controller: GripperController | None = None,
    ) -> None:
        self._name = name
        self._pose = pose
        self.description = description
        self.body = body
        self.kinematics = kinematics
        self._bus = bus
        self.controller_manager = controller_manager
        self.broadcaster = broadcaster
        self.position_controller = position_controller
        self.state_publisher = state_publisher
        self._safety = safety
        self.gripper_controller = gripper_controller
        self._gripper = (
            None if gripper_controller is None else Gripper(name, gripper_controller, bus)
        )

    @property
    def name(self) -> str:
        return self._name

    @property
    def namespace(self) -> str:
        return f"/{self._name}"

    @property
    def model(self) -> str:
        return self.description.model

    @property
    def pose(self) -> SpawnPose:
        """Spawn pose of ``<name>_base_link`` in the world."""
        return self._pose

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Prefixed names of the joints :meth:`move_to` controls, base to tool."""
        return self.position_controller.joint_names

    @property
    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        """(lower, upper) position limits of :attr:`joint_names` [rad or m]."""
        return self.position_controller.lower.copy(), self.position_controller.upper.copy()

    @property
    def gripper(self) -> Gripper:
        """The fingers: ``open()``, ``close(force)``, ``move_to(width)``, ``width``, ``holding``.

        Raises:
            NoGripper: the model has no fingers.
        """
        if self._gripper is None:
            raise NoGripper(self._name, self.model)
        return self._gripper

    @property
    def has_gripper(self) -> bool:
        return self._gripper is not None

    @property
    def joint_state(self) -> JointState:
        """The latest message of ``/<name>/joint_states`` (every movable joint)."""
        latest = self.broadcaster.latest
        assert latest is not None  # bring-up waits for the first message
        return latest

    @property
    def positions(self) -> FloatArray:
        """Current positions of :attr:`joint_names`, read at the last step."""
        positions: FloatArray = self.body.position[self.kinematics.arm_indices].copy()
        return positions

    @property
    def is_moving(self) -> bool:
        """Whether the position controller's reference is still in motion."""
        return self.position_controller.is_moving

    def status(self, stamp: float) -> ArmStatus:
        """What the arm is doing now (also published on ``/<name>/status``)."""
        controller = self.position_controller
        fault = self.controller_manager.fault
        if fault is not None:
            mode, reason = ArmMode.ERROR, fault
        elif controller.stop_reason is not None:
            mode, reason = ArmMode.PROTECTIVE_STOP, controller.stop_reason
        else:
            mode, reason = (ArmMode.MOVING if controller.is_moving else ArmMode.HOLDING), ""
        return ArmStatus(
            stamp, self._name, mode, reason, tuple(controller.saturation_steps.tolist())
        )

    @property
    def mode(self) -> ArmMode:
        return self.status(0.0).mode

    def reset_stop(self) -> None:
        """Accept commands again after a protective stop (the arm holds where it stopped).

        The arm may then move away from what it touches without stopping again.
        """
        self._safety.reset_stop(self)

    def reset(self) -> None:
        """Leave ``error`` (restarting the controllers at the current pose) and any stop."""
        self.controller_manager.reset()
        self._safety.reset_stop(self)

    def move_to(self, positions: Positions) -> None:
        """Send target ``positions`` (one per :attr:`joint_names`); returns at once.

        The command goes out on ``/<name>/position_controller/commands``.

        Raises:
            TargetLengthError, NonFiniteTarget, JointLimitError, MotionLimitError,
            ProtectiveStopError, ArmFault: nothing is sent and the current motion goes on.
        """
        values = self.position_controller.validate(positions)
        if self.controller_manager.fault is not None:
            raise ArmFault(self._name, self.controller_manager.fault)
        self.position_controller.plan(values)
        self._bus.publish(
            f"{self.namespace}/position_controller/commands",
            JointCommand(tuple(float(v) for v in values)),
        )

    def __repr__(self) -> str:
        return f"Arm({self._name!r}, model={self.model!r}, pose={self._pose})"
