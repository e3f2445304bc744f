"""armfleet: several robot arms in one PyBullet world, each in its own namespace.

>>> import armfleet
>>> world = armfleet.World()
>>> bob = world.spawn("bob", model="panda", at=(0, 0))

The public API. Importing it loads the core (PyBullet, Pinocchio, Ruckig, OMPL); the live
API's client and sweeps load on first use (``armfleet.connect``, ``armfleet.sweep``), and
the optional extras (Ray, pyarrow, Foxglove, Gymnasium, PettingZoo, matplotlib) only in
the features that need them. docs/design.md shows the package's rooms.
"""

from typing import TYPE_CHECKING, Any

from armfleet.physics.quiet_pybullet import import_quietly

import_quietly()

from armfleet._version import __version__
from armfleet.arms.arm import Arm
from armfleet.arms.gripper import Gripper
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
from armfleet.frames.spawn_pose import SpawnPose
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
from armfleet.runtime.bus import Bus
from armfleet.spec import FleetSpec, SpecError, load_spec
from armfleet.world import World
from armfleet.world.launch import launch

if TYPE_CHECKING:
    from armfleet.remote import connect
    from armfleet.sweeps.errors import SweepError
    from armfleet.sweeps.sweep import SweepResult, sweep

#: Public names whose package loads on first use: name -> module.
_ON_FIRST_USE = {
    "connect": "armfleet.remote",
    "sweep": "armfleet.sweeps",
    "SweepError": "armfleet.sweeps",
    "SweepResult": "armfleet.sweeps",
}


def __getattr__(name: str) -> Any:
    """Load the live API's client and the sweeps only when first asked for (PEP 562)."""
    module = _ON_FIRST_USE.get(name)
    if module is None:
        raise AttributeError(f"module 'armfleet' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


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
