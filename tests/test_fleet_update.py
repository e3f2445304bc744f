"""The fleet-wide controller update gives the same torques and motions, bit for bit, as each
arm's own controller manager (the plain path, checked against the control law's formula
in test_control_law.py)."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

import armfleet
from armfleet.controllers import fleet_update
from armfleet.controllers.compiled_control import kernel_built
from armfleet.controllers.position_controller import PositionController
from armfleet.messages import ArmMode

#: 30 arms on a 1 m grid: Pandas (with grippers) and, in every tenth place, a UR5 (none).
ARMS = tuple(
    (f"arm{i}", "ur5" if i % 10 == 9 else "panda", (float(i // 6), float(i % 6))) for i in range(30)
)
STEPS = 1500
#: The UR5 that swings through the floor and stops (a protective stop mid-run).
FALLING = "arm9"


Trace = tuple[list[np.ndarray], list[np.ndarray], np.ndarray]


def scripted_run(
    slow_arm: str | None = None, *, compiled: bool = True, count: int = len(ARMS)
) -> Trace:
    """Every arm's efforts and positions at each step of one scripted scene, and the
    saturation counts at its end.

    Every arm has its own gains (a mix-up of per-arm parameters would show) and takes
    random targets every 300 steps. arm0 closes on a box and squeezes it (the
    coupled-finger law) while it moves, other Pandas close on nothing and open again,
    arm1 is pulled into a joint-torque limit (clipping, saturation count), and arm9
    swings into the floor: a protective stop. ``count``: the first that many of ARMS
    (at least 10, so every event happens). ``compiled``: the fleet path's position
    control in the compiled kernel (else in numpy, the reference).
    """
    rng = np.random.default_rng(11)
    with armfleet.World(compiled_control=compiled) as world:
        for index, (name, model, at) in enumerate(ARMS[:count]):
            controller: dict[str, float] = {"kp_s2": 900.0 + 50 * index, "kd_s": 60.0 + index}
            if name == slow_arm:
                controller["update_rate_hz"] = 500.0
            world.spawn(name, model=model, at=at, parameters={"position_controller": controller})
        put_box_between_fingers(world, "arm0")
        arms = list(world.arms.values())
        efforts, positions = [], []
        for step in range(STEPS):
            if step % 300 == 150:
                for arm in arms:
                    if arm.name in ("arm0", FALLING):
                        continue  # arm0 holds its box still; arm19 is falling
                    lower, upper = arm.joint_limits
                    home = np.array(arm.description.home)
                    target = np.clip(home + rng.uniform(-0.4, 0.4, home.size), lower, upper)
                    with contextlib.suppress(armfleet.ArmfleetError):  # e.g. in a stop
                        arm.move_to(target)
            if step == 10:
                world.arm("arm0").gripper.close(force=10.0)
                target = world.arm(FALLING).positions.copy()
                target[1] += 1.8  # swing the upright UR5 down through the floor
                world.arm(FALLING).move_to(target)
            if step % 400 == 100:
                for arm in arms[2::5]:
                    if arm.gripper_controller is not None:
                        arm.gripper.close(force=5.0)
            if step % 400 == 300:
                for arm in arms[2::5]:
                    if arm.gripper_controller is not None:
                        arm.gripper.open()
            if step == 1000:  # a sudden pull on one joint: the torques clip
                trajectory = world.arm("arm1").position_controller.trajectory
                trajectory.position[1] += 0.3  # type: ignore[union-attr]
            world.step()
            efforts.append(np.concatenate([arm.body.effort_command for arm in arms]))
            positions.append(np.concatenate([arm.body.position for arm in arms]))
        saturation = np.concatenate([arm.position_controller.saturation_steps for arm in arms])
        assert world.arm("arm0").gripper.holding  # the squeeze branch ran
        assert world.arm(FALLING).status(world.time).mode is ArmMode.PROTECTIVE_STOP
    assert saturation.sum() > 0  # the pull did clip
    return efforts, positions, saturation


def put_box_between_fingers(world: armfleet.World, arm: str) -> None:
    """A 3 cm box on a static pedestal, centred between ``arm``'s open finger pads."""
    tcp = world.tf.lookup("world", f"{arm}_panda_hand_tcp")[:3, 3]
    side = 0.03
    top = tcp[2] - side / 2
    world.add_object("pedestal", "box", size=(0.08, 0.08, top), mass=0.0, at=(*tcp[:2], top / 2))
    world.add_object("box", "box", size=(side,) * 3, mass=0.2, at=(*tcp[:2], top + side / 2))


def each_arm_on_its_own(monkeypatch: pytest.MonkeyPatch) -> None:
    """From now on every arm is updated by its own controller manager (no fleet path)."""
    monkeypatch.setattr(fleet_update, "_fleet_arm", lambda arm, memory, kernel_index: None)


def assert_identical(fleet: Trace, plain: Trace) -> None:
    for name, a, b in zip(("efforts", "positions"), fleet[:2], plain[:2], strict=True):
        assert len(a) == len(b)
        for step, (x, y) in enumerate(zip(a, b, strict=True)):
            assert np.array_equal(x, y), f"{name} differ at step {step}"
    assert np.array_equal(fleet[2], plain[2]), "saturation counts differ"


def test_fleet_path_equals_each_arm_on_its_own_bit_for_bit(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    fleet = scripted_run(compiled=False, count=10)
    each_arm_on_its_own(monkeypatch)
    assert_identical(fleet, scripted_run(compiled=False, count=10))


def test_compiled_path_agrees_with_the_numpy_path() -> None:
    """The compiled kernel (cpp/fleet_kernel.cpp) against numpy and Pinocchio's bindings:
    efforts and positions to 1e-12 at every step, the same saturation counts. (Both do
    the same floating-point operations; on the development machine they agree bit for
    bit.)"""
    assert kernel_built(), "the compiled fleet path was not built (pip install .)"
    compiled, reference = scripted_run(compiled=True), scripted_run(compiled=False)
    for name, a, b in zip(("efforts", "positions"), compiled[:2], reference[:2], strict=True):
        worst = max(float(np.abs(x - y).max()) for x, y in zip(a, b, strict=True))
        assert worst <= 1e-12, f"{name} differ by {worst:.3e}"
    assert np.array_equal(compiled[2], reference[2]), "saturation counts differ"


def test_an_arm_at_another_rate_beside_the_fleet_path_changes_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """One arm at 500 Hz takes its own path while the others take the fleet path: the
    fleet-wide operations must leave its efforts alone."""
    mixed = scripted_run(slow_arm="arm7", count=10)
    each_arm_on_its_own(monkeypatch)
    assert_identical(mixed, scripted_run(slow_arm="arm7", count=10))


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
