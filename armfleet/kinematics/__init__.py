"""Kinematics: an arm's Pinocchio model, forward kinematics and inverse kinematics.

Owns :class:`ArmKinematics` (the model, its frames and joint indices) and
:mod:`~armfleet.kinematics.inverse_kinematics` (damped least squares within the limits).

Rule: pure computation on a model; imports only :mod:`armfleet.checks` and below (no
PyBullet, no bus).
"""

from armfleet.kinematics.arm_kinematics import ArmKinematics

__all__ = ["ArmKinematics"]
