"""A pose goal: a link of an arm at a pose in a frame, for planned and straight moves."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class PoseGoal:
    """A pose goal: ``link`` of the arm at ``pose`` (4x4 or ``pinocchio.SE3``) in ``frame``."""

    pose: Any
    frame: str = "world"
    link: str = "tool0"
