"""Who owns each frame of a world: every frame has exactly one owner.

An arm owns every link and joint frame of its model (``<name>_base_link``,
``<name>_panda_joint1``, ...), a scene object owns the frame named like it.
Prefixes alone do not keep them apart: arm ``x`` (a Panda) owns
``x_panda_link1``, which arm ``x_panda`` (an xArm7, links ``link1``...) would
own too, and an object may be named ``carol_tool0`` before arm ``carol``
exists. Without one owner per frame, ``tf.lookup`` and every goal given in a
frame silently pick one of the two bodies. So the second claimant is refused,
naming the first.

``world``, the root, is everyone's parent and nobody's property.

The world keeps one registry (:meth:`armfleet.World.spawn` and
:meth:`armfleet.World.add_object` claim, removal releases) and a launch spec
check keeps another for the spec's arms and objects, so both refuse the same.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass

from armfleet.errors import FrameInUse
from armfleet.frames.tf_tree import WORLD_FRAME
from armfleet.kinematics import ArmKinematics


class OwnerKind(enum.Enum):
    """What owns a frame."""

    ARM = "arm"
    OBJECT = "object"


@dataclass(frozen=True)
class FrameOwner:
    """An arm or object that owns frames.

    Attributes:
        kind: arm or object.
        name: its name.
    """

    kind: OwnerKind
    name: str

    @classmethod
    def arm(cls, name: str) -> FrameOwner:
        return cls(OwnerKind.ARM, name)

    @classmethod
    def object(cls, name: str) -> FrameOwner:
        return cls(OwnerKind.OBJECT, name)

    def __str__(self) -> str:
        return f"{self.kind.value} {self.name}"


def arm_frames(kinematics: ArmKinematics) -> tuple[str, ...]:
    """Every frame an arm owns: its links and joints, without the shared ``world``."""
    return tuple(dict.fromkeys(f for f in kinematics.frame_names if f != WORLD_FRAME))


class FrameRegistry:
    """Frame name -> owner, for one world (or one launch spec being checked)."""

    def __init__(self) -> None:
        self._owners: dict[str, FrameOwner] = {}

    def owner(self, frame: str) -> FrameOwner | None:
        """Who owns ``frame``, or None."""
        return self._owners.get(frame)

    def check(self, claimant: FrameOwner, frames: Iterable[str]) -> None:
        """Raise if any of ``frames`` is owned by someone else already (nothing is claimed).

        Raises:
            FrameInUse: naming the first such frame, its owner and the claimant.
        """
        for frame in frames:
            owner = self._owners.get(frame)
            if owner is not None and owner != claimant:
                raise FrameInUse(frame, str(claimant), str(owner))

    def claim(self, claimant: FrameOwner, frames: Iterable[str]) -> None:
        """Make ``claimant`` the owner of ``frames``, all or none.

        Raises:
            FrameInUse: one of them is someone else's; nothing was claimed.
        """
        listed = tuple(frames)
        self.check(claimant, listed)
        for frame in listed:
            self._owners[frame] = claimant

    def release(self, owner: FrameOwner) -> None:
        """Forget every frame of ``owner`` (it left the world); no-op if it owns none."""
        self._owners = {f: o for f, o in self._owners.items() if o != owner}
