"""Where an arm's ``base_link`` sits in the world: x, y, z [m] and yaw [deg]."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from armfleet.errors import PoseError

AT_SYNTAX = "X,Y[,Z[,YAW_DEG]]"


@dataclass(frozen=True)
class SpawnPose:
    """Pose of an arm's base in the world.

    Attributes:
        x, y, z: position of ``<name>_base_link`` [m].
        yaw_deg: rotation about the world z axis [deg].
    """

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw_deg: float = 0.0

    def __post_init__(self) -> None:
        for field, value in (("x", self.x), ("y", self.y), ("z", self.z), ("yaw", self.yaw_deg)):
            if not math.isfinite(value):
                raise PoseError(f"spawn pose {field} is {value}; it must be a finite number")

    @classmethod
    def from_values(cls, values: Sequence[float] | SpawnPose) -> SpawnPose:
        """Build from ``(x, y[, z[, yaw_deg]])``."""
        if isinstance(values, SpawnPose):
            return values
        if isinstance(values, str | bytes) or not 2 <= len(values) <= 4:
            raise PoseError(f"spawn pose {values!r} must be (x, y[, z[, yaw_deg]])")
        try:
            numbers = [float(v) for v in values]
        except (TypeError, ValueError) as exc:
            raise PoseError(f"spawn pose {values!r} must hold numbers: {exc}") from None
        return cls(*numbers)

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

    def matrix(self) -> npt.NDArray[np.float64]:
        """4x4 homogeneous transform world -> base_link."""
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return np.array(
            [[c, -s, 0.0, self.x], [s, c, 0.0, self.y], [0.0, 0.0, 1.0, self.z], [0, 0, 0, 1.0]]
        )

    def __str__(self) -> str:
        return f"({self.x:g}, {self.y:g}, {self.z:g}, yaw {self.yaw_deg:g} deg)"
