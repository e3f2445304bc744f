"""From a :class:`FleetSpec` to a running world: the one path for ``launch`` and ``spawn``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from armfleet.arms.arm import Arm
from armfleet.checks.flags import flag
from armfleet.description import ModelLibrary
from armfleet.errors import ArmfleetError
from armfleet.objects import ObjectSpec, WorldObject
from armfleet.objects.object_arguments import object_arguments
from armfleet.spec import FleetSpec, load_spec
from armfleet.spec.fleet_spec import ArmSpec
from armfleet.spec.scene_rehearsal import rehearse
from armfleet.world import World


def spawn_from_spec(world: World, arm: ArmSpec) -> Arm:
    """Bring up one arm of a spec in ``world``."""
    return world.spawn(
        arm.name,
        arm.model,
        arm.pose,
        initial_positions=arm.initial_positions,
        parameters={name: c.parameters for name, c in arm.controllers.items()},
        parameter_files={name: c.file for name, c in arm.controllers.items() if c.file},
        **arm.options.keywords(),
    )


def add_from_spec(world: World, obj: ObjectSpec) -> WorldObject:
    """Add one object of a spec to ``world``."""
    return world.add_object(obj.name, obj.shape.value, **object_arguments(obj))


def launch(
    spec: FleetSpec | str | Path,
    *,
    viewer: bool | None = None,
    viewer_port: int | None = None,
    before_spawn: Callable[[World], None] | None = None,
    models: ModelLibrary | None = None,
) -> World:
    """Check the whole scene, then create the spec's world, bring its arms up one at a
    time, and add its objects.

    The check (:func:`armfleet.spec.scene_rehearsal.rehearse`) runs before any world
    exists: if the world would refuse any arm or object, nothing comes up.

    Args:
        spec: a spec, or a spec file (path or name of a shipped spec).
        viewer: override the spec's ``world.viewer``.
        viewer_port: web port of the viewer.
        before_spawn: called with the new world before the first arm comes up
            (e.g. to subscribe to ``/bringup``).
        models: the model library to take the arms from; a new one by default. A
            program launching many worlds (a sweep's worker) passes one library to
            all of them: each model's description is then read and expanded once.

    Returns:
        The world with every arm ready and every object in place; close it when done.

    Raises:
        SpecError: a spec file that does not pass ``launch --check``.
        ArmfleetError: the world's own error for the first arm or object of a
            :class:`FleetSpec` it would refuse (e.g. :class:`StartPoseCollision`).
    """
    if viewer is not None:
        viewer = flag(viewer, "viewer")  # before the scene is rehearsed
    if before_spawn is not None and not callable(before_spawn):
        raise ArmfleetError(
            f"launch: before_spawn takes a function of the world (or None), "
            f"got {type(before_spawn).__name__}"
        )
    if models is not None and not isinstance(models, ModelLibrary):
        raise ArmfleetError(
            f"launch: models takes an armfleet.description.ModelLibrary (or None), "
            f"got {type(models).__name__}"
        )
    models = models or ModelLibrary()  # one for the check and the world: templates made once
    if isinstance(spec, FleetSpec):
        rehearse(spec, models)  # a spec file was rehearsed as it was read
    else:
        spec = load_spec(spec)
    settings = spec.world
    world = World(
        dt=settings.dt_s,
        gravity=settings.gravity_m_s2,
        models=models,
        viewer=settings.viewer if viewer is None else viewer,
        viewer_port=viewer_port,
    )
    try:
        if world.viewer is not None:  # framed before any mesh comes, from the first frame
            world.viewer.expect_arms({a.name: (a.pose.x, a.pose.y, a.pose.z) for a in spec.arms})
        if before_spawn is not None:
            before_spawn(world)
        for arm in spec.arms:
            spawn_from_spec(world, arm)
        for obj in spec.objects:
            add_from_spec(world, obj)
    except BaseException:
        world.close()
        raise
    return world
