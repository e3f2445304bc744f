"""A recorded arm, standing in for a live :class:`~armfleet.arms.arm.Arm` in the MeshCat viewer.

The viewer reads an arm's name, description, kinematics, current joint
positions, whether it moves, and its bus (for the target marker and the planned
path): this class
has exactly that, built from the recorded URDF, with positions set by the
replay instead of a physics engine.

The recorded URDF names its meshes by absolute paths on the machine that
recorded it; when they are not here, the arm's model is expanded from this
machine's ``description/`` at the recorded pose, which gives the same arm.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from armfleet.description import ArmDescription, ModelLibrary
from armfleet.errors import ArmfleetError
from armfleet.kinematics import ArmKinematics
from armfleet.messages import FloatArray, Positions
from armfleet.recording.arm_record import ArmRecord
from armfleet.recording.errors import RecordingError
from armfleet.runtime.bus import Bus

logger = logging.getLogger("armfleet")

_MESH = re.compile(r'filename="([^"]+)"')


def usable_urdf(record: ArmRecord, models: ModelLibrary | None = None) -> str:
    """The recorded URDF if its meshes are on this machine, else the model expanded here.

    Raises:
        RecordingError: neither the meshes nor the model are here.
    """
    missing = [
        path
        for path in _MESH.findall(record.urdf)
        if not Path(path.removeprefix("file://")).is_file()
    ]
    if record.urdf and not missing:
        return record.urdf
    models = models or ModelLibrary()
    if record.model in models.names:
        if missing:
            logger.info(
                "%s: recorded meshes not found here; using the local %s", record.name, record.model
            )
        return models.expand(record.model, record.prefix, record.pose).urdf
    first = missing[0] if missing else "(no URDF recorded)"
    raise RecordingError(
        f"cannot show {record.name}: its mesh {first} is not on this machine and its model "
        f"{record.model!r} is not among the local ones ({', '.join(models.names)})"
    )


class _Joints:
    """The ``body`` of a replayed arm: just its joint positions (model order)."""

    def __init__(self, count: int) -> None:
        self.position: FloatArray = np.zeros(count)


class _ControllerContext:
    def __init__(self, bus: Bus) -> None:
        self.bus = bus


class _PositionController:
    """Where the viewer finds the bus carrying the arm's targets and plans, and whether
    the arm moves (from its recorded status) or is in protective stop (never: a replayed
    stop shows as the arm no longer moving)."""

    def __init__(self, bus: Bus) -> None:
        self.arm = _ControllerContext(bus)
        self.is_moving = False
        self.stop_reason: str | None = None


class ReplayArm:
    """One recorded arm, shaped for :meth:`armfleet.viewer.Viewer.add_arm`.

    Args:
        record: the arm as recorded.
        bus: the replay's bus, on which recorded targets are published.
        models: where to find the model when the recorded meshes are missing.

    Raises:
        RecordingError, DescriptionError: the arm cannot be rebuilt here.
    """

    def __init__(self, record: ArmRecord, bus: Bus, models: ModelLibrary | None = None) -> None:
        self.record = record
        self.name = record.name
        self.namespace = f"/{record.name}"
        urdf = usable_urdf(record, models)
        self.description = ArmDescription(record.model, record.prefix, urdf, home=())
        try:
            self.kinematics = ArmKinematics(urdf, self.description.tool0)
        except ArmfleetError as exc:
            raise RecordingError(f"cannot rebuild {record.name} from its URDF: {exc}") from None
        self.body = _Joints(self.kinematics.model.nq)
        self.position_controller = _PositionController(bus)
        self._order: dict[tuple[str, ...], np.ndarray] = {}

    @property
    def is_moving(self) -> bool:
        """Whether the arm moves, as its recorded status says (set by the replay)."""
        return self.position_controller.is_moving

    @is_moving.setter
    def is_moving(self, moving: bool) -> None:
        self.position_controller.is_moving = moving

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Every movable joint, in model order."""
        return self.kinematics.joint_names

    def set_positions(self, names: Sequence[str], positions: Positions) -> None:
        """Take the joint positions of a ``joint_states`` message (by name; others stay)."""
        key = tuple(names)
        order = self._order.get(key)
        if order is None:
            index = {name: i for i, name in enumerate(self.kinematics.joint_names)}
            order = np.array([index.get(name, -1) for name in key])
            self._order[key] = order
        values = np.asarray(positions, dtype=float)
        known = (order >= 0) & np.isfinite(values)
        self.body.position[order[known]] = values[known]

    def __repr__(self) -> str:
        return f"ReplayArm({self.name!r}, model={self.record.model!r})"
