"""Kinematics: an arm's Pinocchio model, forward kinematics and inverse kinematics.

Owns :class:`ArmKinematics` (the model, its frames and joint indices) and
:mod:`~armfleet.kinematics.inverse_kinematics` (damped least squares within the limits).

Rule: pure computation on a model; imports only :mod:`armfleet.checks` and below (no
PyBullet, no bus).
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.kinematics.arm_kinematics import ArmKinematics

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ArmKinematics": "armfleet.kinematics.arm_kinematics",
    },
)

__all__ = ["ArmKinematics"]
