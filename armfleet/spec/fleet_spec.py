"""What a world and its arms are made of, whether typed on a command line or read from YAML."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from armfleet.description.model_options import ModelOptions
from armfleet.errors import ArmfleetError
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.objects.object_spec import ObjectSpec


@dataclass(frozen=True)
class ControllerConfig:
    """One controller of one arm.

    Attributes:
        file: its parameter file; None for the shipped ``controllers/<type>.yaml``.
        parameters: overrides for this arm only, on top of the file.
    """

    file: Path | None = None
    parameters: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class ArmSpec:
    """One arm to bring up.

    Attributes:
        name: arm name, namespace and prefix.
        model: one of the models in ``description/``, a named model of one's own
            (:mod:`armfleet.description.own_models`), or a model file (an absolute path
            or a ``package://`` URI; see :mod:`armfleet.description.file_model`).
        pose: spawn pose of ``<name>_base_link``.
        initial_positions: arm joint positions at spawn [rad or m]; the model's home if None.
        controllers: per controller type (``position_controller``, ...), its configuration.
        options: what is said about a model file: its xacro arguments, tool link,
            gripper joints, home, end effector
            (:class:`~armfleet.description.model_options.ModelOptions`).
    """

    name: str
    model: str = "panda"
    pose: SpawnPose = field(default_factory=SpawnPose)
    initial_positions: tuple[float, ...] | None = None
    controllers: Mapping[str, ControllerConfig] = field(default_factory=dict)
    options: ModelOptions = field(default_factory=ModelOptions)

    def __post_init__(self) -> None:
        if not isinstance(self.options, ModelOptions):  # the xacro_args tuple it replaced
            raise ArmfleetError(
                f"ArmSpec {self.name!r}: options must be an armfleet.description.model_options"
                f".ModelOptions, got {type(self.options).__name__}"
            )

    @property
    def xacro_args(self) -> tuple[tuple[str, str], ...]:
        """``(name, value)`` arguments of a xacro model file (``options.xacro_args``)."""
        return self.options.xacro_args


@dataclass(frozen=True)
class WorldSpec:
    """World settings.

    Attributes:
        dt_s: physics step [s].
        gravity_m_s2: gravitational acceleration along -z [m/s^2].
        realtime: pace the run to the wall clock.
        viewer: start the MeshCat viewer.
    """

    dt_s: float = 0.001
    gravity_m_s2: float = 9.81
    realtime: bool = True
    viewer: bool = True


@dataclass(frozen=True)
class FleetSpec:
    """A world, the arms to bring up in it, in order, and the objects added after them.

    Attributes:
        world: world settings.
        arms: arms in bring-up order.
        source: where the spec came from (a file path or ``"command line"``).
        objects: scene objects (tables, boxes, ...), added once every arm is ready.
    """

    world: WorldSpec = field(default_factory=WorldSpec)
    arms: tuple[ArmSpec, ...] = ()
    source: str = "<python>"
    objects: tuple[ObjectSpec, ...] = ()
