"""What a recording keeps about each arm: name, model, pose, joints, URDF, when it came and went.

The recorder writes one ``armfleet.arms.arm`` metadata record per spawned arm (and
``armfleet.arm_removed`` when one leaves), with the arm's exact URDF as an
attachment named ``<arm>.urdf`` logged at the spawn time. Metadata and
attachments go to the file at once, outside the chunks, so they survive a
crash.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from armfleet.frames.spawn_pose import SpawnPose
from armfleet.recording.errors import RecordingError

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm

ARM_METADATA = "armfleet.arms.arm"
REMOVED_METADATA = "armfleet.arm_removed"
RUN_METADATA = "armfleet.run"
URDF_MEDIA_TYPE = "application/xml"
SPEC_MEDIA_TYPE = "application/yaml"
_POSE_FIELDS = ("x", "y", "z", "yaw_deg", "roll_deg", "pitch_deg")


def urdf_attachment(name: str) -> str:
    """Attachment name of arm ``name``'s URDF."""
    return f"{name}.urdf"


@dataclass(frozen=True)
class ArmRecord:
    """One arm of a recording.

    Attributes:
        name: arm name (namespace ``/<name>``).
        model: model name (``description/<model>.urdf.xacro``).
        prefix: prefix of its links and joints.
        pose: spawn pose of ``<name>_base_link``.
        joint_names: every movable joint, in ``/<name>/joint_states`` order.
        urdf: the URDF the arm was built from (absolute mesh paths of the recording machine).
        spawned_ns: log time of its spawn (or of the recording's start) [ns].
        removed_ns: log time at which it was seen gone, or None [ns].
    """

    name: str
    model: str
    prefix: str
    pose: SpawnPose
    joint_names: tuple[str, ...]
    urdf: str
    spawned_ns: int
    removed_ns: int | None = None

    @property
    def tool0(self) -> str:
        return f"{self.prefix}tool0"

    @property
    def base_link(self) -> str:
        return f"{self.prefix}base_link"


def arm_metadata(arm: Arm, log_time_ns: int) -> dict[str, str]:
    """The ``armfleet.arms.arm`` record of a live arm."""
    pose = arm.pose
    return {
        "name": arm.name,
        "model": arm.model,
        "prefix": arm.description.prefix,
        **{field: repr(float(getattr(pose, field))) for field in _POSE_FIELDS},
        "joint_names": " ".join(arm.kinematics.joint_names),
        "spawned_ns": str(log_time_ns),
        "urdf_attachment": urdf_attachment(arm.name),
    }


def arm_record(values: dict[str, str], urdf: str, removed_ns: int | None) -> ArmRecord:
    """An :class:`ArmRecord` from its ``armfleet.arms.arm`` metadata and URDF."""
    try:
        return ArmRecord(
            name=values["name"],
            model=values["model"],
            prefix=values["prefix"],
            pose=SpawnPose(**{field: float(values[field]) for field in _POSE_FIELDS}),
            joint_names=tuple(values["joint_names"].split()),
            urdf=urdf,
            spawned_ns=int(values["spawned_ns"]),
            removed_ns=removed_ns,
        )
    except (KeyError, ValueError) as exc:
        raise RecordingError(f"malformed {ARM_METADATA} record ({exc}): {values}") from None
