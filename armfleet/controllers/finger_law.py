"""The gripper controller's law for fingers that are not yet squeezing, on arrays.

The fleet path runs it over every finger of every gripper at once. A single gripper
runs the same law on plain floats (``GripperController.update``: for two fingers,
numpy's per-call overhead costs more than the arithmetic). The two do the same
floating-point operations in the same order, and ``fmax``/``fmin`` pick as Python's
``max``/``min`` do (a NaN effort gives way to the limit), so they agree bit for bit
(``tests/test_fleet_update.py``).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from armfleet.messages import FloatArray


def finger_efforts(
    q: FloatArray,
    v: FloatArray,
    reference: tuple[FloatArray, FloatArray, FloatArray],
    mass: FloatArray,
    stiffness: FloatArray,
    gain: FloatArray,
    damping: FloatArray,
    force: FloatArray,
    blocked: npt.NDArray[np.bool_],
) -> FloatArray:
    """Per finger, ``m a_ref + k (q_ref - q) + c (v_ref - v) + damping v`` clipped to
    ``[-force, force]``, or ``-force`` (pressing closed) where the finger is blocked.

    Args:
        q, v: measured positions [m] and velocities [m/s].
        reference: the reference positions, velocities and accelerations.
        mass: mass moved by each finger [kg].
        stiffness, gain: position [N/m] and velocity [N s/m] feedback.
        damping: the URDF's viscous damping [N s/m], compensated.
        force: force limit of each finger now [N].
        blocked: fingers held up by something while closing.
    """
    position, velocity, acceleration = reference
    effort = mass * acceleration + stiffness * (position - q) + gain * (velocity - v) + damping * v
    np.fmin(force, np.fmax(-force, effort), out=effort)
    pressing: FloatArray = np.where(blocked, -force, effort)
    return pressing
