"""The compiled fleet path: every fleet arm's position-control law in one C++ call.

``cpp/fleet_kernel.cpp`` (built on ``pip install``) does, for each arm on its columns
of the joint memory, what the numpy fleet path does: the PD feedback, RNEA (Pinocchio's
own, on a copy of the arm's model rebuilt from its numbers), the damping compensation,
the clipping to the effort limits and the saturation flags. In Python the same costs
two numpy passes over the memory plus a call into Pinocchio per arm (about 3.5 µs per
Panda); the kernel costs about 1.3 µs per Panda (docs/performance.md).

The numpy path stays as the reference (``World(compiled_control=False)``), and serves
arms whose joints the kernel does not know (a joint that is not revolute or prismatic,
a configuration space larger than the velocity space). The two agree to 1e-12
(``tests/test_compiled_control.py``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from armfleet.kinematics import ArmKinematics
from armfleet.physics.joint_memory import JointMemory, Row

try:  # built by `pip install`; a source tree that was never built has none
    from armfleet.controllers._fleet_kernel import FleetKernel
except ImportError:  # pragma: no cover - the test command always builds it
    FleetKernel = None

#: The rows the kernel reads and writes, in the order its constructor takes them.
KERNEL_ROWS = (
    Row.POSITION,
    Row.VELOCITY,
    Row.EFFORT_COMMAND,
    Row.REFERENCE_POSITION,
    Row.REFERENCE_VELOCITY,
    Row.REFERENCE_ACCELERATION,
    Row.KP,
    Row.KD,
    Row.DAMPING,
    Row.EFFORT_LIMIT,
    Row.NEGATIVE_EFFORT_LIMIT,
    Row.ACCELERATION,
    Row.TORQUE,
)

#: Pinocchio joints the kernel rebuilds (one configuration value per velocity).
KERNEL_JOINTS = frozenset(
    {
        "JointModelRX",
        "JointModelRY",
        "JointModelRZ",
        "JointModelRevoluteUnaligned",
        "JointModelPX",
        "JointModelPY",
        "JointModelPZ",
        "JointModelPrismaticUnaligned",
    }
)


def kernel_built() -> bool:
    """Whether the compiled fleet path is installed."""
    return FleetKernel is not None


def kernel_can_model(kinematics: ArmKinematics) -> bool:
    """Whether the kernel can rebuild this arm's model (only joints it knows)."""
    model = kinematics.model
    return model.nq == model.nv and all(
        model.joints[j].shortname() in KERNEL_JOINTS for j in range(1, model.njoints)
    )


class CompiledControl:
    """The kernel of one lay-out of the joint memory.

    Args:
        memory: the world's joint memory (laid out).
        arms: per arm, its kinematics and its first column, in column order.
    """

    def __init__(self, memory: JointMemory, arms: Sequence[tuple[ArmKinematics, int]]) -> None:
        assert FleetKernel is not None  # callers check kernel_built()
        self._memory = memory
        self._kernel = FleetKernel([int(row) for row in KERNEL_ROWS])
        #: Per arm (in the order given): its index in the kernel, or None (numpy path).
        self.indices: list[int | None] = []
        for kinematics, start in arms:
            if kernel_can_model(kinematics):
                self.indices.append(self._add(kinematics, start))
            else:
                self.indices.append(None)

    def _add(self, kinematics: ArmKinematics, start: int) -> int:
        model = kinematics.model
        joints = range(1, model.njoints)
        kinds = [model.joints[j].shortname() for j in joints]
        axes = [
            tuple(float(x) for x in model.joints[j].extract().axis)
            if kind.endswith("Unaligned")
            else (0.0, 0.0, 0.0)
            for j, kind in zip(joints, kinds, strict=True)
        ]
        placements = np.array([model.jointPlacements[j].homogeneous for j in joints])
        inertias = np.array([_inertia_numbers(model.inertias[j]) for j in joints])
        index: int = self._kernel.add_arm(
            [int(model.parents[j]) for j in joints],
            kinds,
            axes,
            np.ascontiguousarray(placements),
            np.ascontiguousarray(inertias),
            tuple(float(g) for g in model.gravity.linear),
            np.ascontiguousarray(model.armature, dtype=float),
            start,
        )
        return index

    def control(self, indices: npt.NDArray[np.int64], half_step_s: float) -> None:
        """The law of the arms ``indices`` (kernel indices) into the memory: efforts,
        torques, accelerations, and the saturation flags (False in every other column)."""
        memory = self._memory
        memory.saturated[:] = False
        self._kernel.control(memory.block, indices, half_step_s, memory.saturated)

    def rnea(self, index: int, q: npt.ArrayLike, v: npt.ArrayLike, a: npt.ArrayLike) -> object:
        """RNEA of one arm in the kernel (for tests against Pinocchio's bindings)."""
        return self._kernel.rnea(index, q, v, a)


def _inertia_numbers(inertia: pin.Inertia) -> list[float]:
    """Mass, lever (3) and the rotational inertia about the centre of mass (9, by rows)."""
    return [float(inertia.mass), *map(float, inertia.lever), *map(float, inertia.inertia.ravel())]
