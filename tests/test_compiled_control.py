"""The compiled fleet path (cpp/fleet_kernel.cpp via armfleet/controllers/compiled_control.py).

Its RNEA is checked against Pinocchio's own Python bindings on every shipped model, and
a world is shown to use it (and the numpy reference only when asked). Whole runs of 30
arms are compared with the numpy path in tests/test_fleet_update.py.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from armfleet.controllers.compiled_control import CompiledControl, kernel_built
from armfleet.description import ModelLibrary
from armfleet.kinematics import ArmKinematics
from armfleet.messages import ArmMode

MODELS = ModelLibrary().names


@pytest.mark.parametrize("model", MODELS)
def test_kernel_rnea_equals_pinocchio_bindings(model: str) -> None:
    """The kernel rebuilds each arm's model from its numbers: the same torques as
    ``pin.rnea`` on the Python model, at random states, to 1e-12 N m."""
    assert kernel_built(), "the compiled fleet path was not built (pip install .)"
    with armfleet.World() as world:
        arm = world.spawn("bob", model=model)
        kinematics = arm.kinematics
        kernel = CompiledControl(world._memory, [(kinematics, 0)])
        assert kernel.indices == [0]
        model_ = kinematics.model
        data = model_.createData()
        rng = np.random.default_rng(3)
        worst = 0.0
        for _ in range(200):
            q = rng.uniform(kinematics.lower, kinematics.upper)
            v, a = rng.uniform(-3, 3, model_.nv), rng.uniform(-20, 20, model_.nv)
            expected = pin.rnea(model_, data, q, v, a)
            worst = max(worst, float(np.abs(np.asarray(kernel.rnea(0, q, v, a)) - expected).max()))
        assert worst <= 1e-12


def test_worlds_use_the_kernel_and_the_numpy_path_only_when_asked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With Pinocchio's Python RNEA broken, a default world's arms still track (the kernel
    computes their torques); with ``compiled_control=False`` the arm that uses it faults,
    alone, as any controller that raises (its neighbour keeps moving)."""

    def broken(self: ArmKinematics, *args: object) -> np.ndarray:
        raise RuntimeError("solver diverged")

    monkeypatch.setattr(ArmKinematics, "rnea", broken)
    with armfleet.World() as world:
        bob = world.spawn("bob")
        bob.move_to(bob.positions + 0.2)
        world.run(1.0)
        assert bob.status(world.time).mode is ArmMode.HOLDING
        assert bob.position_controller.tracking_error < 1e-3
    monkeypatch.undo()
    with armfleet.World(compiled_control=False) as world:
        bob = world.spawn("bob")
        toby = world.spawn("toby", model="ur5", at=(1.0, 0.0))
        monkeypatch.setattr(bob.kinematics, "rnea", broken.__get__(bob.kinematics))
        toby.move_to(toby.positions + 0.2)
        bob.move_to(bob.positions + 0.2)
        world.run(1.0)
        assert bob.status(world.time).mode is ArmMode.ERROR
        assert "solver diverged" in bob.status(world.time).reason
        assert toby.status(world.time).mode is ArmMode.HOLDING
        assert toby.position_controller.tracking_error < 1e-3


def test_compiled_control_must_be_a_flag() -> None:
    with pytest.raises(armfleet.ArmfleetError, match="compiled_control"):
        armfleet.World(compiled_control="yes")  # type: ignore[arg-type]
