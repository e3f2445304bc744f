"""Putting one arm together: its body in PyBullet, its controllers, its transforms."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from armfleet.arms.arm import Arm
from armfleet.controllers import (
    ArmContext,
    ControllerManager,
    JointStateBroadcaster,
    PositionController,
)
from armfleet.controllers.gripper_controller import GripperController
from armfleet.controllers.gripper_joints import gripper_joints
from armfleet.controllers.parameters import load_parameters
from armfleet.controllers.position_controller import check_target
from armfleet.controllers.registry import CONTROLLER_TYPES
from armfleet.description import ArmDescription
from armfleet.errors import DescriptionError, ParameterError
from armfleet.frames.robot_state_publisher import RobotStatePublisher
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray, Positions
from armfleet.physics.collision_filter import filter_collisions
from armfleet.physics.start_clearance import Neighbour, load_clear_body
from armfleet.runtime.bus import Bus
from armfleet.runtime.lifetime import Lifetime
from armfleet.safety.safety_supervisor import SafetySupervisor

if TYPE_CHECKING:
    from armfleet.planning import MotionPlanner

ControllerOverrides = Mapping[str, Mapping[str, Any]]


def check_controller_parameters(
    parameters: Mapping[str, Any], parameter_files: Mapping[str, str | os.PathLike[str]]
) -> dict[str, Path]:
    """Validate every controller's file and overrides before any part of the arm exists.

    Returns:
        ``parameter_files`` with every path as a :class:`~pathlib.Path`.

    Raises:
        ParameterError: either argument not a mapping, a file that is not a path,
            unknown controller, overrides that are not a mapping, or a
            file/override that does not fit the controller's schema.
    """
    for argument, given, meaning in (
        ("parameters", parameters, "{controller: {parameter: value}}"),
        ("parameter_files", parameter_files, "{controller: path of a .yaml file}"),
    ):
        if not isinstance(given, Mapping):
            raise ParameterError(
                f"{argument} must be a mapping {meaning}, got {type(given).__name__} "
                f"{given!r}; controllers: {', '.join(CONTROLLER_TYPES)}"
            )
    files: dict[str, Path] = {}
    for controller, file in parameter_files.items():
        if not isinstance(file, str | os.PathLike):
            raise ParameterError(
                f"parameter_files[{controller!r}] must be the path of a .yaml file "
                f"(str or Path), got {type(file).__name__} {file!r}"
            )
        files[controller] = Path(file)
    unknown = (set(parameters) | set(files)) - set(CONTROLLER_TYPES)
    if unknown:
        raise ParameterError(
            f"parameters for unknown controllers {', '.join(sorted(map(str, unknown)))}; "
            f"valid: {', '.join(CONTROLLER_TYPES)}"
        )
    for controller, controller_type in CONTROLLER_TYPES.items():
        overrides = parameters.get(controller, {})
        if not isinstance(overrides, Mapping):
            raise ParameterError(
                f"parameters for {controller} must be a mapping of name: value, "
                f"got {type(overrides).__name__}"
            )
        load_parameters(
            controller, controller_type.parameter_schema, files.get(controller), overrides
        )
    return files


def start_positions(
    name: str, kinematics: ArmKinematics, home: Sequence[float], initial: Positions | None
) -> FloatArray:
    """Every movable joint's position at spawn: ``initial`` (checked) or the model's home
    for the arm joints, mid-range for the others (a Panda's gripper half open).

    Off their limits: a joint resting on a limit keeps a limit constraint busy in
    the physics solver at every step.
    """
    lower, upper = kinematics.lower, kinematics.upper
    start = kinematics.mid_range()
    arm = kinematics.arm_indices
    if len(home) != len(arm):
        raise DescriptionError(f"home pose has {len(home)} values for {len(arm)} arm joints")
    start[arm] = home
    if initial is not None:
        # Same checks, same messages as a motion target.
        names = [kinematics.joint_names[i] for i in arm]
        start[arm] = check_target(name, initial, names, lower[arm], upper[arm])
    return start


def assemble_arm(
    *,
    name: str,
    pose: SpawnPose,
    description: ArmDescription,
    kinematics: ArmKinematics,
    start: FloatArray,
    client: int,
    ground: int,
    bus: Bus,
    dt: float,
    stamp: float,
    safety: SafetySupervisor,
    on_fault: Callable[[str], None],
    parameters: ControllerOverrides,
    parameter_files: Mapping[str, Path],
    frame_pose: Callable[[str], FloatArray] | None = None,
    lifetime: Lifetime | None = None,
    neighbours: Iterable[Neighbour] = (),
    planner: MotionPlanner | None = None,
    compiled: bool = True,
) -> Arm:
    """Load the body (brakes on, at ``start``) and configure its controllers.

    First of all, the body is refused if at ``start`` it would touch itself or any of
    the ``neighbours`` (:mod:`armfleet.physics.start_clearance`): :class:`StartPoseCollision`.

    ``frame_pose`` gives the world pose (4x4) of any frame the world knows
    (e.g. ``world.tf.world_pose``): Cartesian goals may be given in them.
    ``lifetime`` is the arm's (see :mod:`armfleet.runtime.lifetime`), ended by the world.
    ``planner`` plans its collision-free motions (the world's). ``compiled``: its
    references step in compiled code where it is built (the world's choice).

    Both parameter sets are validated before the arm is returned; on any error
    the body is removed again and the world is as it was.
    """
    body = load_clear_body(
        client, name, description.urdf, kinematics.joint_names, start,
        description.ignored_contacts, neighbours,
    )  # fmt: skip
    try:
        filter_collisions(client, body, ground, description.ignored_contacts)
        context = ArmContext(name, body, kinematics, bus, dt, compiled)
        manager = ControllerManager(context, on_fault=on_fault)
        broadcaster = JointStateBroadcaster(
            context,
            parameter_files.get(JointStateBroadcaster.type_name),
            parameters.get(JointStateBroadcaster.type_name),
        )
        controller = PositionController(
            context,
            parameter_files.get(PositionController.type_name),
            parameters.get(PositionController.type_name),
        )
        manager.load(broadcaster)
        manager.load(controller)
        broadcaster.configure()
        controller.configure()
        gripper = None
        joints = gripper_joints(kinematics, description.urdf, description.gripper_joints)
        if joints.leaders.size:
            gripper = GripperController(
                context,
                parameter_files.get(GripperController.type_name),
                parameters.get(GripperController.type_name),
                position_controller=controller,
                joints=joints,
            )
            manager.load(gripper)
            gripper.configure()
    except BaseException:
        body.remove()
        raise
    publisher = RobotStatePublisher(name, kinematics, bus, stamp)
    return Arm(
        name, pose, description, body, kinematics, bus, manager, broadcaster, controller,
        publisher, safety, gripper, frame_pose, lifetime, planner,
    )  # fmt: skip
