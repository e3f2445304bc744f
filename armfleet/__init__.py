"""armfleet: several robot arms in one PyBullet world, each in its own namespace.

>>> import armfleet
>>> world = armfleet.World()
>>> bob = world.spawn("bob", model="panda", at=(0, 0))
"""

from armfleet.quiet_pybullet import import_quietly

import_quietly()

from armfleet.arm import Arm
from armfleet.bus import Bus
from armfleet.errors import (
    ArmfleetError,
    ArmInMotion,
    FrameInUse,
    GripperCommandError,
    InvalidFlag,
    InvalidNumber,
    NameInUse,
    NoGripper,
    ObjectCollision,
    ObjectError,
    StartPoseCollision,
    TargetPoseError,
    UnknownArm,
    UnknownObject,
    UnreachablePose,
    WorldBusy,
    WorldClosed,
)
from armfleet.gripper import Gripper
from armfleet.launch import launch
from armfleet.messages import (
    ArmMode,
    BringupEvent,
    BringupStage,
    ControllerState,
    GripperCommand,
    GripperMode,
    GripperState,
    JointCommand,
    JointState,
    PlannedMotion,
    TFMessage,
    TransformStamped,
)
from armfleet.objects import WorldObject
from armfleet.planning import FailureReason, Plan, PlanningFailed, PoseGoal
from armfleet.recording import (
    Recorder,
    Recording,
    RecordingError,
    open_recording,
    plot_recording,
    record,
)
from armfleet.remote import connect
from armfleet.spawn_pose import SpawnPose
from armfleet.spec import FleetSpec, SpecError, load_spec
from armfleet.sweeps import SweepError, SweepResult, sweep
from armfleet.world import World

__version__ = "0.1.0"

__all__ = [
    "Arm",
    "ArmInMotion",
    "ArmMode",
    "ArmfleetError",
    "BringupEvent",
    "BringupStage",
    "Bus",
    "ControllerState",
    "FailureReason",
    "FleetSpec",
    "FrameInUse",
    "Gripper",
    "GripperCommand",
    "GripperCommandError",
    "GripperMode",
    "GripperState",
    "InvalidFlag",
    "InvalidNumber",
    "JointCommand",
    "JointState",
    "NameInUse",
    "NoGripper",
    "ObjectCollision",
    "ObjectError",
    "Plan",
    "PlannedMotion",
    "PlanningFailed",
    "PoseGoal",
    "Recorder",
    "Recording",
    "RecordingError",
    "SpawnPose",
    "SpecError",
    "StartPoseCollision",
    "SweepError",
    "SweepResult",
    "TFMessage",
    "TargetPoseError",
    "TransformStamped",
    "UnknownArm",
    "UnknownObject",
    "UnreachablePose",
    "World",
    "WorldBusy",
    "WorldClosed",
    "WorldObject",
    "__version__",
    "connect",
    "launch",
    "load_spec",
    "open_recording",
    "plot_recording",
    "record",
    "sweep",
]
