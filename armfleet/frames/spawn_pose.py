"""Where an arm's ``base_link`` sits in the world: x, y, z [m], yaw (and roll, pitch) [deg]."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from armfleet.checks.number_ranges import ANGLE_DEG, WORLD_COORDINATE_M
from armfleet.checks.real_numbers import is_real, is_real_vector
from armfleet.errors import PoseError

AT_SYNTAX = "X,Y[,Z[,YAW_DEG]]"


@dataclass(frozen=True)
class SpawnPose:
    """Pose of an arm's base in the world.

    Attributes:
        x, y, z: position of ``<name>_base_link`` [m].
        yaw_deg: rotation about the world z axis [deg].
        roll_deg, pitch_deg: rotations about x and y [deg] (URDF ``rpy``: the
            orientation is Rz(yaw) Ry(pitch) Rx(roll)), for wall or ceiling mounts.
    """

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw_deg: float = 0.0
    roll_deg: float = 0.0
    pitch_deg: float = 0.0

    def __post_init__(self) -> None:
        fields = (
            ("x", self.x), ("y", self.y), ("z", self.z),
            ("yaw", self.yaw_deg), ("roll", self.roll_deg), ("pitch", self.pitch_deg),
        )  # fmt: skip
        for field, value in fields:
            if not is_real(value):
                raise PoseError(f"spawn pose {field} is {value!r}; it must be a finite number")
            if not math.isfinite(value):
                raise PoseError(f"spawn pose {field} is {value}; it must be a finite number")
            valid = WORLD_COORDINATE_M if field in ("x", "y", "z") else ANGLE_DEG
            if not valid.contains(value):
                raise PoseError(f"spawn pose {field} is {value:g}; give {valid.valid}")

    @classmethod
    def from_values(cls, values: Sequence[float] | SpawnPose) -> SpawnPose:
        """Build from ``(x, y[, z[, yaw_deg]])`` [m, deg], numbers (not text or bool)."""
        if isinstance(values, SpawnPose):
            return values
        if not is_real_vector(values) or not 2 <= len(values) <= 4:
            raise PoseError(
                f"spawn pose {values!r} must be (x, y[, z[, yaw_deg]]) of numbers [m, deg], "
                "or a SpawnPose"
            )
        return cls(*(float(v) for v in values))

    @classmethod
    def parse(cls, text: str) -> SpawnPose:
        """Parse the CLI form ``X,Y[,Z[,YAW_DEG]]``, e.g. ``1,0`` or ``1,0,0.3,90``."""
        parts = text.split(",")
        if not 2 <= len(parts) <= 4:
            raise PoseError(
                f"--at {text!r} is malformed; expected {AT_SYNTAX}, e.g. 1,0 or 1,0,0,90"
            )
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            raise PoseError(
                f"--at {text!r} is malformed; expected numbers as {AT_SYNTAX}, e.g. 1,0,0,90"
            ) from None
        return cls(*numbers)

    @property
    def yaw_rad(self) -> float:
        return math.radians(self.yaw_deg)

    @property
    def rpy_rad(self) -> tuple[float, float, float]:
        """(roll, pitch, yaw) [rad], as in a URDF ``<origin rpy=...>``."""
        return (math.radians(self.roll_deg), math.radians(self.pitch_deg), self.yaw_rad)

    def matrix(self) -> npt.NDArray[np.float64]:
        """4x4 homogeneous transform world -> base_link."""
        roll, pitch, yaw = self.rpy_rad
        cr, sr = math.cos(roll), math.sin(roll)
        cp, sp = math.cos(pitch), math.sin(pitch)
        cy, sy = math.cos(yaw), math.sin(yaw)
        rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
        rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
        matrix = np.eye(4)
        matrix[:3, :3] = rz @ ry @ rx
        matrix[:3, 3] = (self.x, self.y, self.z)
        return matrix

    def __str__(self) -> str:
        tilt = f", roll {self.roll_deg:g}, pitch {self.pitch_deg:g}" if self.tilted else ""
        return f"({self.x:g}, {self.y:g}, {self.z:g}, yaw {self.yaw_deg:g} deg{tilt})"

    @property
    def tilted(self) -> bool:
        return self.roll_deg != 0.0 or self.pitch_deg != 0.0
