"""A launch spec's scene, rehearsed before any world exists: frame owners and start clearance.

The world refuses an arm whose frame another body owns
(:mod:`armfleet.frame_registry`) or that would touch something at its start
configuration (:mod:`armfleet.start_clearance`). A spec that ``--check`` calls
ok must not be refused later, half brought up; so the spec's arms and objects
go through the very same two rules here, in a scratch PyBullet client (DIRECT,
no controllers, no time) with its own floor and contact monitor:

1. every arm claims its frames, in order, then every object its own (an
   object named like an arm's frame is refused at the object's line);
2. the objects are placed, then the arms one by one at their start
   configurations, each checked against itself, the floor, the objects and the
   arms placed before it.

Objects go in before the arms here, although ``launch`` adds them after the
arms are ready: what is asked is whether the finished scene is clear, and an
arm standing inside a table is as wrong after its bring-up as before.

Cost: about 12 ms per Panda (expansion, kinematics, loading the body), so
0.4 s for the 30-arm grid.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import TracebackType
from typing import NoReturn

import pybullet as p

from armfleet.arm_assembly import start_positions
from armfleet.bus import Bus
from armfleet.contact_monitor import ContactMonitor
from armfleet.description import ArmDescription, ModelLibrary
from armfleet.errors import ArmfleetError, StartPoseCollision
from armfleet.frame_registry import FrameOwner, FrameRegistry, arm_frames
from armfleet.ground import create_ground
from armfleet.kinematics import ArmKinematics
from armfleet.located_yaml import LocatedDict
from armfleet.messages import FloatArray
from armfleet.objects.object_spec import ObjectSpec
from armfleet.objects.world_object import WorldObject
from armfleet.spec.fleet_spec import ArmSpec
from armfleet.spec.spec_reader import SpecReader
from armfleet.start_clearance import load_clear_body


@dataclass(frozen=True)
class _PlannedArm:
    spec: ArmSpec
    entry: LocatedDict
    field: str
    description: ArmDescription
    kinematics: ArmKinematics
    start: FloatArray


class SceneRehearsal:
    """The scratch world of one spec check; use it in a ``with`` block.

    Args:
        reader: the spec's reader (errors name its file and lines).
        models: the model library the spec's models come from.
    """

    def __init__(self, reader: SpecReader, models: ModelLibrary) -> None:
        self._reader = reader
        self._models = models
        self._client: int = p.connect(p.DIRECT)
        self._contacts = ContactMonitor(
            self._client, create_ground(self._client), Bus(), lambda contact, deeper: None
        )
        self._frames = FrameRegistry()
        self._arms: list[_PlannedArm] = []

    def add_arm(self, arm: ArmSpec, entry: LocatedDict, field: str) -> None:
        """Claim the frames of ``arm`` (checked by :func:`check_fleet` already).

        Raises:
            SpecError: at the arm's name, if another arm owns one of its frames.
        """
        description = self._models.expand(arm.model, f"{arm.name}_", arm.pose)
        kinematics = ArmKinematics(description.urdf, description.tool0)
        try:
            start = start_positions(arm.name, kinematics, description.home, arm.initial_positions)
            self._frames.claim(FrameOwner.arm(arm.name), arm_frames(kinematics))
        except ArmfleetError as exc:
            key = "initial_positions" if "initial_positions" in entry else "name"
            self._fail(entry, field, key, exc)
        self._arms.append(_PlannedArm(arm, entry, field, description, kinematics, start))

    def add_object(self, obj: ObjectSpec, entry: LocatedDict, field: str) -> None:
        """Claim the frame of ``obj`` and place it.

        Raises:
            SpecError: at the object's name, if an arm owns a frame named like it.
        """
        try:
            self._frames.claim(FrameOwner.object(obj.name), (obj.name,))
        except ArmfleetError as exc:
            self._fail(entry, field, "name", exc)
        body = WorldObject(obj, self._client)
        self._contacts.add_object(obj.name, body.body_id, static=obj.is_static)

    def place_arms(self) -> None:
        """Place the arms in order, each at its start configuration, if it touches nothing.

        Raises:
            SpecError: at the arm's pose (``at_m``, or the grid's ``spacing_m``), naming
                what the arm would touch; at its ``initial_positions`` if it is itself.
        """
        for arm in self._arms:
            try:
                body = load_clear_body(
                    self._client,
                    arm.spec.name,
                    arm.description.urdf,
                    arm.kinematics.joint_names,
                    arm.start,
                    arm.description.ignored_contacts,
                    self._contacts.neighbours(),
                )
            except ArmfleetError as exc:
                # Folded into itself: its initial positions; touching something else: its pose.
                itself = isinstance(exc, StartPoseCollision) and exc.other == arm.spec.name
                keys = ["initial_positions"] if itself else []
                keys += ["at_m", "spacing_m", "initial_positions"]
                given = [k for k in keys if k in arm.entry]
                self._fail(arm.entry, arm.field, given[0] if given else "name", exc)
            self._contacts.add_arm(arm.spec.name, body)

    def _fail(self, entry: LocatedDict, field: str, key: str, exc: ArmfleetError) -> NoReturn:
        raise self._reader.error(entry.line_of(key), f"{field}.{key}", str(exc)) from None

    def close(self) -> None:
        p.disconnect(physicsClientId=self._client)

    def __enter__(self) -> SceneRehearsal:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
