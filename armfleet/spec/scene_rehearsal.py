"""A fleet's scene, rehearsed before any world exists: names, frame owners and clearance.

The world refuses an arm whose frame another body owns
(:mod:`armfleet.frames.frame_registry`) or that would touch something at its start
configuration (:mod:`armfleet.physics.start_clearance`), and an object that would touch
an arm or overlap the floor or an object (:mod:`armfleet.objects.object_clearance`). A
fleet that passes here must not be refused later, half brought up; so every
launch (:func:`armfleet.launch`, whether the spec comes from a file, from Python
or from ``armfleet spawn``'s command line) and every ``launch --check`` puts the
fleet's arms and objects through the very same rules first, in a scratch
PyBullet client (DIRECT, no controllers, no time) with its own floor and
contact monitor:

1. every arm claims its frames, in order, then every object its own (an
   object named like an arm's frame is refused at the object's line);
2. the objects are placed, each checked against the floor and the objects
   before it, then the arms one by one at their start configurations, each
   checked against itself, the floor, the objects and the arms placed before it.

Objects go in before the arms here, although ``launch`` adds them after the
arms are ready: what is asked is whether the finished scene is clear, and the
rules judge an arm and an object the same whichever comes first.

:class:`SceneRehearsal` raises the world's own errors;
:class:`LocatedRehearsal` turns them into a :class:`SpecError` at the line of a
spec file to change.

Cost: about 12 ms per Panda (expansion, kinematics, loading the body), so
0.4 s for the 30-arm grid.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import TracebackType
from typing import NoReturn

import pybullet as p

from armfleet.arms.arm_assembly import check_controller_parameters, start_positions
from armfleet.checks.located_yaml import LocatedDict
from armfleet.checks.names import check_arm_name
from armfleet.description import ArmDescription, ModelLibrary
from armfleet.errors import (
    ArmfleetError,
    NameInUse,
    ObjectCollision,
    ObjectError,
    StartPoseCollision,
)
from armfleet.frames.frame_registry import FrameOwner, FrameRegistry, arm_frames
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray
from armfleet.objects.object_arguments import object_arguments
from armfleet.objects.object_clearance import place_clear_object
from armfleet.objects.object_spec import ObjectSpec, object_spec
from armfleet.physics.contact_monitor import ContactMonitor
from armfleet.physics.ground import create_ground
from armfleet.physics.start_clearance import load_clear_body
from armfleet.runtime.bus import Bus
from armfleet.spec.fleet_spec import ArmSpec, FleetSpec, WorldSpec
from armfleet.spec.spec_error import SpecError
from armfleet.spec.spec_reader import SpecReader


@dataclass(frozen=True)
class _PlannedArm:
    spec: ArmSpec
    description: ArmDescription
    kinematics: ArmKinematics
    start: FloatArray


class SceneRehearsal:
    """The scratch world of one check; use it in a ``with`` block.

    Args:
        models: the model library the arms' models come from (the shipped one by default).
    """

    def __init__(self, models: ModelLibrary | None = None) -> None:
        self._models = models or ModelLibrary()
        self._client: int = p.connect(p.DIRECT)
        self._contacts = ContactMonitor(
            self._client, create_ground(self._client), Bus(), lambda contact, deeper: None
        )
        self._frames = FrameRegistry()
        self._arms: dict[str, _PlannedArm] = {}
        self._objects: list[str] = []

    def add_arm(self, arm: ArmSpec) -> None:
        """Check the arm as :meth:`armfleet.World.spawn` would, and claim its frames.

        Raises:
            ArmfleetError: the world's error: a bad or repeated name, an unknown
                model, bad initial positions or controller parameters, or a frame
                another arm owns (:class:`FrameInUse`).
        """
        check_arm_name(arm.name, self._arms)
        pose = SpawnPose.from_values(arm.pose)  # as spawn takes it: (x, y[, z[, yaw]]) too
        check_controller_parameters(
            {name: c.parameters for name, c in arm.controllers.items()},
            {name: c.file for name, c in arm.controllers.items() if c.file},
        )
        description = self._models.expand(arm.model, f"{arm.name}_", pose, options=arm.options)
        kinematics = ArmKinematics(description.urdf, description.tool0)
        start = start_positions(arm.name, kinematics, description.home, arm.initial_positions)
        self._frames.claim(FrameOwner.arm(arm.name), arm_frames(kinematics))
        self._arms[arm.name] = _PlannedArm(arm, description, kinematics, start)

    def add_object(self, obj: ObjectSpec) -> None:
        """Claim the frame of ``obj`` and place it, if it is clear of the floor and the
        objects placed before it.

        Raises:
            ObjectError: a bad field (an ``ObjectSpec`` built by hand is checked again).
            NameInUse: an arm or an object has its name.
            FrameInUse: an arm owns a frame named like it.
            ObjectCollision: it would overlap the floor or an object.
        """
        obj = object_spec(obj.name, obj.shape, **object_arguments(obj))  # as add_object does
        if obj.name in self._arms or obj.name in self._objects:
            kind = "an arm" if obj.name in self._arms else "an object"
            raise NameInUse(obj.name, kind, list(self._arms), self._objects)
        owner = FrameOwner.object(obj.name)
        self._frames.claim(owner, (obj.name,))
        try:
            body = place_clear_object(self._client, obj, self._contacts.neighbours())
        except BaseException:
            self._frames.release(owner)
            raise
        self._contacts.add_object(obj.name, body.body_id, static=obj.is_static)
        self._objects.append(obj.name)

    def place_arm(self, name: str) -> None:
        """Place the arm ``name`` (added before) at its start configuration, if it
        touches nothing there: itself, the floor, the objects and the arms placed before.

        Raises:
            StartPoseCollision: naming what the arm would touch.
        """
        arm = self._arms[name]
        body = load_clear_body(
            self._client,
            name,
            arm.description.urdf,
            arm.kinematics.joint_names,
            arm.start,
            arm.description.ignored_contacts,
            self._contacts.neighbours(),
        )
        self._contacts.add_arm(name, body)

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


def rehearse(spec: FleetSpec, models: ModelLibrary | None = None) -> None:
    """Raise the error the world would raise bringing up ``spec``, before any world exists.

    Raises:
        ArmfleetError: the first arm or object the world would refuse, with the
            world's own error (:class:`StartPoseCollision`, :class:`ObjectCollision`,
            :class:`FrameInUse`, ...).
    """
    _check_entries(spec)
    with SceneRehearsal(models) as scene:
        for arm in spec.arms:
            scene.add_arm(arm)
        for obj in spec.objects:
            scene.add_object(obj)
        for arm in spec.arms:
            scene.place_arm(arm.name)


class LocatedRehearsal:
    """:class:`SceneRehearsal` for a spec file: each refusal is a :class:`SpecError` at
    the line to change. Use it in a ``with`` block.

    Args:
        reader: the spec's reader (errors name its file and lines).
        models: the model library the spec's models come from.
    """

    def __init__(self, reader: SpecReader, models: ModelLibrary) -> None:
        self._reader = reader
        self._scene = SceneRehearsal(models)
        self._arms: list[tuple[ArmSpec, LocatedDict, str]] = []

    def add_arm(self, arm: ArmSpec, entry: LocatedDict, field: str) -> None:
        """Claim the frames of ``arm`` (checked by :func:`check_fleet` already).

        Raises:
            SpecError: at the arm's name (or initial positions), if the world would refuse it.
        """
        try:
            self._scene.add_arm(arm)
        except ArmfleetError as exc:
            key = "initial_positions" if "initial_positions" in entry else "name"
            self._fail(entry, field, key, exc)
        self._arms.append((arm, entry, field))

    def add_object(self, obj: ObjectSpec, entry: LocatedDict, field: str) -> None:
        """Claim the frame of ``obj`` and place it.

        Raises:
            SpecError: at the object's pose (``at_m``) if it would overlap the floor or
                an object placed before it; at its mesh if PyBullet cannot load it; at
                its name if an arm owns a frame named like it.
        """
        try:
            self._scene.add_object(obj)
        except ArmfleetError as exc:
            keys = ["at_m"] if isinstance(exc, ObjectCollision) else []
            keys += ["mesh"] if isinstance(exc, ObjectError) and exc.field == "mesh" else []
            given = [k for k in keys if k in entry]
            self._fail(entry, field, given[0] if given else "name", exc)

    def place_arms(self) -> None:
        """Place the arms in order, each at its start configuration, if it touches nothing.

        Raises:
            SpecError: at the arm's pose (``at_m``, or the grid's ``spacing_m``), naming
                what the arm would touch; at its ``initial_positions`` if it is itself.
        """
        for arm, entry, field in self._arms:
            try:
                self._scene.place_arm(arm.name)
            except ArmfleetError as exc:
                # Folded into itself: its initial positions; touching something else: its pose.
                itself = isinstance(exc, StartPoseCollision) and exc.other == arm.name
                keys = ["initial_positions"] if itself else []
                keys += ["at_m", "spacing_m", "initial_positions"]
                given = [k for k in keys if k in entry]
                self._fail(entry, field, given[0] if given else "name", exc)

    def _fail(self, entry: LocatedDict, field: str, key: str, exc: ArmfleetError) -> NoReturn:
        raise self._reader.error(entry.line_of(key), f"{field}.{key}", str(exc)) from None

    def close(self) -> None:
        self._scene.close()

    def __enter__(self) -> LocatedRehearsal:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def _check_entries(spec: FleetSpec) -> None:
    """A FleetSpec built by hand holds what its fields say (the dataclass checks
    nothing): an arm given as a dict escaped as an AttributeError from the check."""
    if not isinstance(spec.world, WorldSpec):
        got = type(spec.world).__name__
        raise SpecError(spec.source, 0, "world", f"must be an armfleet.spec.WorldSpec, got {got}")
    for field, entries, kind in (
        ("arms", spec.arms, ArmSpec),
        ("objects", spec.objects, ObjectSpec),
    ):
        if not isinstance(entries, tuple | list):
            raise SpecError(
                spec.source,
                0,
                field,
                f"must be a tuple of {kind.__name__}, got {type(entries).__name__}",
            )
        for index, entry in enumerate(entries):
            if not isinstance(entry, kind):
                raise SpecError(
                    spec.source,
                    0,
                    f"{field}[{index}]",
                    f"must be an armfleet.spec.{kind.__name__}, got {type(entry).__name__}",
                )
