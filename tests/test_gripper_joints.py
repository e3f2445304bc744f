"""A description's gripper joints driven by the gripper controller: revolute jaws (SO-100,
by path), mimic joints that follow their leader (example-robot-data's panda.urdf, and
tests/data/mimic_jaw_arm.urdf: two revolute jaws, the right one mimicking the left with
multiplier -1), and the fleet paths agreeing on them."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.controllers.gripper_joints import gripper_joints
from armfleet.errors import DescriptionError, GripperCommandError
from armfleet.messages import GripperMode
from tests.test_fleet_update import assert_identical, each_arm_on_its_own
from tests.test_own_robot import TRACKING_RAD, UPSTREAM

MIMIC_JAW_ARM = Path(__file__).parent / "data" / "mimic_jaw_arm.urdf"
#: The Panda's finger2 follows finger1 through an open and a close to this [m].
PANDA_FOLLOWER_M = 1e-4
#: The mimic jaw follows its leader, in free motion, to this [rad]: the coupling's spring
#: (jaw_stiffness_s2 / (1 + m^2) per unit of inertia) accelerating the follower at the
#: jaws' acceleration limit, 2 * 20 / 1.3e5 = 3.1e-4 rad.
JAW_FOLLOWER_RAD = 5e-4
#: Squeezing, the pair's coupling settles to this [rad] (the grasp torque, 1 N m, against
#: the coupling's spring, 7 N m/rad, shared by the two jaws' contacts).
SQUEEZED_FOLLOWER_RAD = 1e-3
BOX_SIDE_M = 0.04


def _spawn(world: armfleet.World, name: str, model: Path, x: float = 0.0) -> armfleet.Arm:
    return world.spawn(name, model=str(model), at=(x, 0.0))


def test_pinocchio_keeps_a_mimic_joint_a_joint_of_its_own() -> None:
    """armfleet assumes one independent q per movable joint: Pinocchio must not fold the
    mimic into its leader (it does with ``mimic=True``)."""
    with armfleet.World() as world:
        arm = _spawn(world, "bob", UPSTREAM["panda"])
        model = arm.kinematics.model
        assert "bob_panda_finger_joint2" in arm.kinematics.joint_names
        assert model.nq == model.nv == len(arm.kinematics.joint_names) == 9
        controller = arm.gripper_controller
        assert controller is not None
        assert controller.finger_names == ("bob_panda_finger_joint1",)  # the leader


@pytest.fixture(scope="module")
def so100() -> Iterator[armfleet.World]:
    """SO-100 by path: one revolute joint, ``gripper``, moves its jaw."""
    with armfleet.World() as world:
        _spawn(world, "bob", UPSTREAM["so100"])
        yield world


def test_a_revolute_jaw_goes_to_commanded_angles_and_closes(so100: armfleet.World) -> None:
    arm = so100.arm("bob")
    gripper = arm.gripper
    lower, upper = arm.kinematics.lower[-1], arm.kinematics.upper[-1]
    assert (gripper.max_width, arm.gripper_controller.min_width) == (upper, lower)  # type: ignore[union-attr]
    jaw = arm.kinematics.joint_names.index("bob_gripper")
    for angle in (1.5, 0.3, 1.0):
        gripper.move_to(angle)
        so100.run(2.5)
        assert gripper.mode is GripperMode.AT_WIDTH
        assert abs(arm.body.position[jaw] - angle) < TRACKING_RAD
        assert gripper.width == arm.body.position[jaw]  # the opening is the jaw's angle
    gripper.close()
    so100.run(2.5)
    assert gripper.mode is GripperMode.CLOSED  # on nothing: at its lower limit
    assert abs(gripper.width - lower) < TRACKING_RAD
    gripper.open()
    so100.run(2.5)
    assert abs(gripper.width - upper) < TRACKING_RAD
    assert arm.mode is armfleet.ArmMode.HOLDING


@pytest.mark.parametrize(
    ("width", "force"),
    [
        pytest.param(2.5, None, id="an angle past the upper limit"),
        pytest.param(-0.5, None, id="an angle past the lower limit"),
        pytest.param(1.0, 40.0, id="a torque over the effort limit"),
    ],
)
def test_a_bad_jaw_command_names_radians_and_newton_metres(
    so100: armfleet.World, width: float, force: float | None
) -> None:
    with pytest.raises(GripperCommandError) as raised:
        so100.arm("bob").gripper.move_to(width, force=force)
    unit = "N m" if force is not None else "rad"
    assert f"] {unit}" in str(raised.value)


def test_the_panda_urdf_mimic_finger_tracks_its_leader() -> None:
    with armfleet.World() as world:
        arm = _spawn(world, "bob", UPSTREAM["panda"])
        gripper = arm.gripper
        leader, follower = (
            arm.kinematics.joint_names.index(f"bob_panda_finger_joint{i}") for i in (1, 2)
        )
        worst = 0.0

        def watch(_: armfleet.World) -> None:
            nonlocal worst
            q = arm.body.position
            worst = max(worst, abs(float(q[follower] - q[leader])))

        assert gripper.max_width == pytest.approx(0.08)  # both fingers count, as shipped
        for command, width in ((gripper.open, 0.08), (gripper.close, 0.0)):
            command()
            world.run(1.0, on_step=watch)
            assert abs(gripper.width - width) < 2e-4
        gripper.move_to(0.05)
        world.run(1.0, on_step=watch)
        assert abs(gripper.width - 0.05) < 2e-4
        assert worst < PANDA_FOLLOWER_M


def _mirror_error(arm: armfleet.Arm) -> float:
    """|right + left|: the mimic (multiplier -1) is off its leader by this [rad]."""
    q = arm.body.position
    names = arm.kinematics.joint_names
    left, right = (names.index(f"{arm.name}_{side}_jaw_joint") for side in ("left", "right"))
    return abs(float(q[right] + q[left]))


def test_a_mimic_jaw_mirrors_its_leader_throughout() -> None:
    with armfleet.World() as world:
        arm = _spawn(world, "bob", MIMIC_JAW_ARM)
        gripper = arm.gripper
        worst = 0.0

        def watch(_: armfleet.World) -> None:
            nonlocal worst
            worst = max(worst, _mirror_error(arm))

        commands: list[Callable[[], None]] = [
            gripper.open, gripper.close, lambda: gripper.move_to(0.2)
        ]  # fmt: skip
        for command in commands:
            command()
            world.run(1.0, on_step=watch)
        assert abs(gripper.width - 0.2) < TRACKING_RAD
        assert worst < JAW_FOLLOWER_RAD
        assert arm.mode is armfleet.ArmMode.HOLDING  # the jaws meeting nothing is no contact


def _box_between_jaws(world: armfleet.World, arm: str) -> None:
    """A box on a narrow static pedestal, between ``arm``'s open jaws (they hang 8 cm)."""
    tool = world.tf.lookup("world", f"{arm}_tool0")[:3, 3]
    top = tool[2] - 0.04 - BOX_SIDE_M / 2
    at = (float(tool[0]), float(tool[1]))
    world.add_object(f"{arm}_pedestal", "box", size=(0.02, 0.02, top), mass=0.0, at=(*at, top / 2))
    world.add_object(
        f"{arm}_box", "box", size=(BOX_SIDE_M,) * 3, mass=0.1, at=(*at, top + BOX_SIDE_M / 2)
    )


def test_revolute_jaws_closing_on_a_box_stop_blocked_and_lift_it() -> None:
    with armfleet.World() as world:
        arm = _spawn(world, "bob", MIMIC_JAW_ARM)
        gripper = arm.gripper
        gripper.open()
        world.run(1.0)
        _box_between_jaws(world, "bob")
        world.run(0.3)
        gripper.close(force=1.0)
        world.run(1.0)
        state = gripper.state(world.time)
        assert state.mode is GripperMode.SQUEEZING and state.holding
        assert gripper.width > arm.gripper_controller.min_width + 0.1  # type: ignore[union-attr]
        assert gripper.force == pytest.approx(1.0, abs=0.01)  # N m
        assert _mirror_error(arm) < SQUEEZED_FOLLOWER_RAD
        box = world.object("bob_box")
        before = float(box.position[2])
        arm.move_to(arm.positions + np.array([0.0, -0.3]))  # lift the beam
        world.run(2.0)
        assert gripper.holding
        assert box.position[2] > before + 0.05


def _scripted_jaws(*, compiled: bool) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """Four grippers with followers (two mimic jaw arms, two panda.urdf): the fleet's
    one pass over every gripper runs. One squeezes a box, the others open and close."""
    with armfleet.World(compiled_control=compiled) as world:
        for i in range(4):
            model = MIMIC_JAW_ARM if i % 2 == 0 else UPSTREAM["panda"]
            _spawn(world, f"arm{i}", model, x=float(i))
        arms = list(world.arms.values())
        for arm in arms:
            arm.gripper.open()
        world.run(0.8)
        _box_between_jaws(world, "arm0")
        efforts, positions = [], []
        for step in range(900):
            if step == 50:
                for arm in arms:
                    arm.gripper.close()
            if step == 500:
                arms[1].gripper.move_to(0.03)
                arms[2].gripper.open()
                arms[0].move_to(arms[0].positions + np.array([0.2, -0.2]))
            world.step()
            efforts.append(np.concatenate([arm.body.effort_command for arm in arms]))
            positions.append(np.concatenate([arm.body.position for arm in arms]))
        assert arms[0].gripper.holding
        saturation = np.concatenate([arm.position_controller.saturation_steps for arm in arms])
    return efforts, positions, saturation


def test_the_fleet_paths_drive_followers_and_jaws_as_each_arm_alone(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    compiled = _scripted_jaws(compiled=True)
    fleet = _scripted_jaws(compiled=False)
    for a, b in zip(compiled[0], fleet[0], strict=True):  # the kernel against numpy
        assert float(np.abs(a - b).max()) <= 1e-12
    each_arm_on_its_own(monkeypatch)
    assert_identical(fleet, _scripted_jaws(compiled=False))


@pytest.mark.parametrize(
    "named",
    [
        pytest.param(("bob_lift",), id="an arm joint"),
        pytest.param(("bob_thumb_joint",), id="a joint the arm does not have"),
    ],
)
def test_gripper_joints_off_the_arm_are_refused_in_one_line(named: tuple[str, ...]) -> None:
    with armfleet.World() as world:
        arm = _spawn(world, "bob", MIMIC_JAW_ARM)
        with pytest.raises(DescriptionError, match="valid: bob_left_jaw_joint, bob_right_jaw"):
            gripper_joints(arm.kinematics, arm.description.urdf, named)
