"""armfleet: several robot arms in one PyBullet world, each in its own namespace.

>>> import armfleet
>>> world = armfleet.World()
>>> bob = world.spawn("bob", model="panda", at=(0, 0))

The public API. Importing it loads the errors and the messages; every other name
loads its room on first use (``armfleet.World``: the simulator; ``armfleet.connect``: the
live API's client; ``armfleet.sweep``: Ray), and the optional extras (Ray, pyarrow,
Foxglove, Gymnasium, PettingZoo, matplotlib) only in the features that need them.
docs/design.md shows the package's rooms.
"""

from typing import TYPE_CHECKING

from armfleet.physics.quiet_import_hook import install as _install_quiet_pybullet

_install_quiet_pybullet()  # PyBullet loads, without its banner, where it is first imported

from armfleet._version import __version__
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
    SelfContactError,
    StartPoseCollision,
    TargetPoseError,
    UnknownArm,
    UnknownObject,
    UnreachablePose,
    WorldBusy,
    WorldClosed,
)
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
from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.arms.arm import Arm
    from armfleet.arms.gripper import Gripper
    from armfleet.frames.spawn_pose import SpawnPose
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
    from armfleet.runtime.bus import Bus
    from armfleet.spec import FleetSpec, SpecError, load_spec
    from armfleet.sweeps.errors import SweepError
    from armfleet.sweeps.sweep import SweepResult, sweep
    from armfleet.world import World
    from armfleet.world.launch import launch

# Everything but the errors and messages loads on first use, so that `import armfleet` (and
# a command-line call that only talks to a running world) starts without the simulator.
__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Arm": "armfleet.arms.arm",
        "Gripper": "armfleet.arms.gripper",
        "SpawnPose": "armfleet.frames.spawn_pose",
        "WorldObject": "armfleet.objects",
        "FailureReason": "armfleet.planning",
        "Plan": "armfleet.planning",
        "PlanningFailed": "armfleet.planning",
        "PoseGoal": "armfleet.planning",
        "Recorder": "armfleet.recording",
        "Recording": "armfleet.recording",
        "RecordingError": "armfleet.recording",
        "open_recording": "armfleet.recording",
        "plot_recording": "armfleet.recording",
        "record": "armfleet.recording",
        "Bus": "armfleet.runtime.bus",
        "FleetSpec": "armfleet.spec",
        "SpecError": "armfleet.spec",
        "load_spec": "armfleet.spec",
        "World": "armfleet.world",
        "launch": "armfleet.world.launch",
        "connect": "armfleet.remote",
        "sweep": "armfleet.sweeps",
        "SweepError": "armfleet.sweeps",
        "SweepResult": "armfleet.sweeps",
    },
)

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
    "SelfContactError",
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
