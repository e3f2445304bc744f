"""Checks of a spec's arms: names, models, joint limits, controller parameters.

They use the same checks as :meth:`armfleet.World.spawn`, so a spec that passes
``armfleet launch --check`` brings up without a surprise. Whether arms touch
each other, the floor or the objects, and who owns each frame, is asked after
these by :mod:`armfleet.spec.scene_rehearsal`, with the world's own rules.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NoReturn

from armfleet.checks.located_yaml import LocatedDict
from armfleet.checks.model_reference import is_model_file
from armfleet.checks.names import check_arm_name
from armfleet.controllers.parameters import load_parameters
from armfleet.controllers.position_controller import check_target
from armfleet.controllers.registry import CONTROLLER_TYPES
from armfleet.description import ModelLibrary
from armfleet.errors import ArmfleetError
from armfleet.kinematics import ArmKinematics
from armfleet.spec.fleet_spec import ArmSpec
from armfleet.spec.spec_reader import SpecReader

LocatedArm = tuple[ArmSpec, LocatedDict, str]


def check_fleet(
    reader: SpecReader, arms: Sequence[LocatedArm], models: ModelLibrary | None = None
) -> None:
    """Raise :class:`SpecError` at the first arm that cannot be brought up as specified."""
    models = models or ModelLibrary()
    available = models.available
    limits: dict[str, ArmKinematics] = {}
    seen: dict[str, ArmSpec] = {}
    for arm, entry, field in arms:

        def fail(
            key: str, problem: str, entry: LocatedDict = entry, field: str = field
        ) -> NoReturn:
            raise reader.error(entry.line_of(key), f"{field}.{key}", problem)

        try:
            check_arm_name(arm.name)
        except ArmfleetError as exc:
            fail("name", str(exc))
        if arm.name in seen:
            fail("name", f"arm name {arm.name!r} is used twice; names must be unique")
        if is_model_file(arm.model):
            try:
                models.path(arm.model, options=arm.options)  # read and expanded once here
            except ArmfleetError as exc:
                fail("model", str(exc))
        elif arm.model not in available:
            fail("model", f"model {arm.model!r} not found; available: {', '.join(available)}")
        else:
            try:
                models.path(arm.model, options=arm.options)  # one's own: its settings read
            except ArmfleetError as exc:
                fail("model", str(exc))
        seen[arm.name] = arm
        if arm.initial_positions is not None:
            key = f"{arm.model} {arm.options}"
            if key not in limits:
                description = models.expand(arm.model, "", options=arm.options)
                limits[key] = ArmKinematics(description.urdf, description.tool0)
            kinematics = limits[key]
            chain = kinematics.arm_indices
            try:
                check_target(
                    arm.name,
                    arm.initial_positions,
                    [f"{arm.name}_{kinematics.joint_names[i]}" for i in chain],
                    kinematics.lower[chain],
                    kinematics.upper[chain],
                )
            except ArmfleetError as exc:
                fail("initial_positions", str(exc))
        for controller, config in arm.controllers.items():
            try:
                load_parameters(
                    controller,
                    CONTROLLER_TYPES[controller].parameter_schema,
                    config.file,
                    config.parameters,
                )
            except ArmfleetError as exc:  # a problem inside the controller file
                fail("controllers", str(exc))
