"""The fleet-wide controller update gives the same torques and motions, bit for bit, as each
arm's own controller manager (the plain path, checked against the control law's formula
in test_control_law.py)."""

from __future__ import annotations

import numpy as np
import pytest

import armfleet
from armfleet.controllers import fleet_update
from armfleet.controllers.position_controller import PositionController

ARMS = (("bob", "panda", (0.0, 0.0)), ("toby", "panda", (1.0, 0.0)), ("ursula", "ur5", (0.0, 1.0)))
#: Each arm its own gains, so a mix-up of per-arm parameters would show.
GAINS = {"bob": (2500.0, 100.0), "toby": (900.0, 60.0), "ursula": (1600.0, 80.0)}


Trace = tuple[list[np.ndarray], list[np.ndarray], np.ndarray]


def scripted_run(slow_arm: str | None = None) -> Trace:
    """Every arm's efforts and positions at each step of one scripted scene, and the
    saturation counts at its end.

    The scene moves every arm with random targets, closes and opens bob's gripper, and
    pushes one arm (bob) into a joint-torque limit so clipping and saturation count.
    """
    rng = np.random.default_rng(11)
    with armfleet.World() as world:
        for name, model, at in ARMS:
            kp, kd = GAINS[name]
            controller: dict[str, float] = {"kp_s2": kp, "kd_s": kd}
            if name == slow_arm:
                controller["update_rate_hz"] = 500.0
            world.spawn(name, model=model, at=at, parameters={"position_controller": controller})
        arms = list(world.arms.values())
        bob = world.arm("bob")
        assert bob.gripper is not None
        efforts, positions = [], []
        for step in range(1500):
            if step % 300 == 0:
                for arm in arms:
                    lower, upper = arm.joint_limits
                    home = np.array(arm.description.home)
                    arm.move_to(np.clip(home + rng.uniform(-0.5, 0.5, home.size), lower, upper))
            if step == 200:
                bob.gripper.close(force=10.0)
            if step == 700:
                bob.gripper.open()
            if step == 1000:  # a sudden pull on one joint: the torques clip
                bob.position_controller.trajectory.position[1] += 0.3  # type: ignore[union-attr]
            world.step()
            efforts.append(np.concatenate([arm.body.effort_command for arm in arms]))
            positions.append(np.concatenate([arm.body.position for arm in arms]))
        saturation = np.concatenate([arm.position_controller.saturation_steps for arm in arms])
    assert saturation.sum() > 0  # the pull did clip
    return efforts, positions, saturation


def each_arm_on_its_own(monkeypatch: pytest.MonkeyPatch) -> None:
    """From now on every arm is updated by its own controller manager (no fleet path)."""
    monkeypatch.setattr(fleet_update, "_fleet_arm", lambda arm: None)


def assert_identical(fleet: Trace, plain: Trace) -> None:
    for name, a, b in zip(("efforts", "positions"), fleet[:2], plain[:2], strict=True):
        assert len(a) == len(b)
        for step, (x, y) in enumerate(zip(a, b, strict=True)):
            assert np.array_equal(x, y), f"{name} differ at step {step}"
    assert np.array_equal(fleet[2], plain[2]), "saturation counts differ"


def test_fleet_path_equals_each_arm_on_its_own_bit_for_bit(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    fleet = scripted_run()
    each_arm_on_its_own(monkeypatch)
    assert_identical(fleet, scripted_run())


def test_an_arm_at_another_rate_beside_the_fleet_path_changes_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """One arm at 500 Hz takes its own path while the others take the fleet path: the
    fleet-wide operations must leave its efforts alone."""
    mixed = scripted_run(slow_arm="toby")
    each_arm_on_its_own(monkeypatch)
    assert_identical(mixed, scripted_run(slow_arm="toby"))


def test_standard_arms_take_the_fleet_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """Once up, no arm's position controller is updated on its own: the fleet path runs."""
    calls: list[str] = []
    original = PositionController.update

    def counted(self: PositionController, stamp: float) -> None:
        calls.append(self.arm.name)
        original(self, stamp)

    monkeypatch.setattr(PositionController, "update", counted)
    with armfleet.World() as world:
        world.spawn("bob")
        world.spawn("toby", model="ur5", at=(1.0, 0.0))
        calls.clear()
        world.arm("toby").move_to(world.arm("toby").positions + 0.1)
        world.run(0.2)
        assert calls == []
        assert world.arm("toby").position_controller.tracking_error < 1e-3
