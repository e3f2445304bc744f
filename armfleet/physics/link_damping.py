"""Bullet's hidden link damping, turned off on every body armfleet creates.

Bullet gives every link of a multibody (and its base) a linear and an angular
damping of 0.04 unless told otherwise. It is not in the URDF, ``getDynamicsInfo``
does not report it, and no model (Pinocchio's RNEA, which the position controller
uses) knows of it: on a moving Panda it changed the accelerations by up to
0.53 rad/s² (about 0.6 N·m) and made half the tracking error. Free objects lost
speed to it in flight. With it off, PyBullet's forward dynamics agree with
``pinocchio.aba`` on the upstream model to about 1e-8 of the accelerations
(``tests/test_dynamics_reference.py``): the physics is the URDF's, joint damping
and all, and nothing else.
"""

from __future__ import annotations

import pybullet as p


def disable_link_damping(body_id: int, client: int) -> None:
    """Set Bullet's linear and angular damping to zero on every link of ``body_id`` and its
    base (link -1), in the PyBullet world ``client``."""
    for link in range(-1, p.getNumJoints(body_id, physicsClientId=client)):
        p.changeDynamics(
            body_id, link, linearDamping=0.0, angularDamping=0.0, physicsClientId=client
        )
