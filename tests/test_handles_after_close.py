"""Handles after ``world.close()`` or ``world.remove(arm)`` (issue #14, item 9).

An :class:`armfleet.Arm`, its :class:`armfleet.Gripper`, the world's ``tf`` and a
:class:`armfleet.WorldObject` stand for something in one world. Once the world is
closed, everything that reads or commands them raises :class:`WorldClosed`; once
the arm is removed, its handle and its gripper raise :class:`UnknownArm`, even when
a new arm of the same name has come up (which must not move); a removed object's
handle raises :class:`UnknownObject` likewise. That includes an arm's parts that live
in the world (``body``, ``kinematics``, controllers, ``ik``). What a handle *is*
(name, model, joint names and limits, description; an object's shape and size)
stays readable.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Iterator
from types import FunctionType
from typing import Any

import numpy as np
import pytest

import armfleet
from armfleet.errors import ArmfleetError, UnknownArm, UnknownObject, WorldClosed
from armfleet.frames.tf_tree import TfTree
from armfleet.messages import GripperCommand, JointCommand
from armfleet.remote import RemoteError
from tests.test_remote_python_server import Served, served  # noqa: F401  (served: a fixture)

#: A settled arm's joints drift less than this over 0.2 s [rad] (test_bad_input's figure).
HOLD_DRIFT_RAD = 1e-4
HOLD_CHECK_S = 0.2

Use = Callable[[armfleet.Arm, armfleet.World, Any], object]


def tool0(world: armfleet.World) -> np.ndarray:
    """A pose a Panda at the origin reaches: 0.4 m ahead, 0.4 m up, pointing down."""
    del world  # the same pose whatever the world (and even once it is closed)
    return np.array([[1, 0, 0, 0.4], [0, -1, 0, 0.0], [0, 0, -1, 0.4], [0, 0, 0, 1.0]])


#: Every use of an arm handle that reads or commands the arm (``g``: its gripper,
#: taken while the arm was in the world).
ARM_USES: list[Any] = [
    pytest.param(lambda a, w, g: a.move_to(np.zeros(7) - [0, 0.5, 0, 2, 0, -1.5, 0]),
                 id="move_to"),
    pytest.param(lambda a, w, g: a.move_to_pose(tool0(w)), id="move_to_pose"),
    pytest.param(lambda a, w, g: a.move_to_pose(tool0(w), linear=True), id="move_to_pose linear"),
    pytest.param(lambda a, w, g: a.solve_ik(tool0(w)), id="solve_ik"),
    pytest.param(lambda a, w, g: a.reset(), id="reset"),
    pytest.param(lambda a, w, g: a.reset_stop(), id="reset_stop"),
    pytest.param(lambda a, w, g: a.positions, id="positions"),
    pytest.param(lambda a, w, g: a.joint_state, id="joint_state"),
    pytest.param(lambda a, w, g: a.is_moving, id="is_moving"),
    pytest.param(lambda a, w, g: a.mode, id="mode"),
    pytest.param(lambda a, w, g: a.status(0.0), id="status"),
    pytest.param(lambda a, w, g: a.gripper, id="gripper"),
    pytest.param(lambda a, w, g: g.close(), id="gripper.close"),
    pytest.param(lambda a, w, g: g.open(), id="gripper.open"),
    pytest.param(lambda a, w, g: g.move_to(0.02), id="gripper.move_to"),
    pytest.param(lambda a, w, g: g.width, id="gripper.width"),
    pytest.param(lambda a, w, g: g.force, id="gripper.force"),
    pytest.param(lambda a, w, g: g.mode, id="gripper.mode"),
    pytest.param(lambda a, w, g: g.holding, id="gripper.holding"),
    pytest.param(lambda a, w, g: g.is_moving, id="gripper.is_moving"),
    pytest.param(lambda a, w, g: g.state(), id="gripper.state"),
    # Its parts that live in the world: stale once it is gone (issue #14, item 9).
    pytest.param(lambda a, w, g: a.body, id="body"),
    pytest.param(lambda a, w, g: a.kinematics, id="kinematics"),
    pytest.param(lambda a, w, g: a.controller_manager, id="controller_manager"),
    pytest.param(lambda a, w, g: a.position_controller, id="position_controller"),
    pytest.param(lambda a, w, g: a.broadcaster, id="broadcaster"),
    pytest.param(lambda a, w, g: a.state_publisher, id="state_publisher"),
    pytest.param(lambda a, w, g: a.gripper_controller, id="gripper_controller"),
    pytest.param(lambda a, w, g: a.ik, id="ik"),
]  # fmt: skip


def still_readable(arm: armfleet.Arm, gripper: armfleet.Gripper) -> None:
    """What the handle is, not what the arm does, stays available."""
    assert arm.name == "bob" and arm.model == "panda"
    assert len(arm.joint_names) == 7 and arm.joint_limits[0].shape == (7,)
    assert repr(arm).startswith("Arm('bob'") and repr(gripper).startswith("Gripper(")
    assert arm.description.model == "panda" and arm.description.prefix == "bob_"
    assert gripper.max_width > 0.0 and gripper.min_width == 0.0
    assert (gripper.width_unit, gripper.force_unit) == ("m", "N")


@pytest.fixture
def closed() -> Iterator[tuple[armfleet.World, armfleet.Arm, armfleet.Gripper]]:
    world = armfleet.World()
    bob = world.spawn("bob")
    gripper = bob.gripper
    world.close()
    yield world, bob, gripper


@pytest.mark.parametrize("use", ARM_USES)
def test_after_close_every_use_of_an_arm_raises_world_closed(
    closed: tuple[armfleet.World, armfleet.Arm, armfleet.Gripper], use: Use
) -> None:
    world, bob, gripper = closed
    with pytest.raises(WorldClosed, match=r"this world is closed; create a new armfleet\.World"):
        use(bob, world, gripper)
    still_readable(bob, gripper)


@pytest.mark.parametrize(
    "use",
    [
        pytest.param(lambda w: w.tf.lookup("world", "bob_tool0"), id="tf.lookup"),
        pytest.param(lambda w: w.tf.world_pose("bob_tool0"), id="tf.world_pose"),
        pytest.param(lambda w: w.step(), id="step"),
        pytest.param(lambda w: w.run(0.1), id="run"),
        pytest.param(lambda w: w.move_together({"bob": np.zeros(7)}), id="move_together"),
        pytest.param(lambda w: w.spawn("toby"), id="spawn"),
        pytest.param(lambda w: w.remove("bob"), id="remove"),
        pytest.param(lambda w: w.record("run.mcap"), id="record"),
    ],
)
def test_after_close_the_world_and_its_tf_raise_world_closed(
    closed: tuple[armfleet.World, armfleet.Arm, armfleet.Gripper],
    use: Callable[[armfleet.World], object],
    tmp_path: Any,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(WorldClosed):
        use(closed[0])


#: Every use of an object handle that reads or moves the object.
OBJECT_USES = [
    pytest.param(lambda o: o.pose, id="pose"),
    pytest.param(lambda o: o.position, id="position"),
    pytest.param(lambda o: o.velocity, id="velocity"),
    pytest.param(lambda o: o.angular_velocity, id="angular_velocity"),
    pytest.param(lambda o: o.set_pose((2, 0, 0.5)), id="set_pose"),
    pytest.param(lambda o: o.body_id, id="body_id (PyBullet may give it to a new body)"),
]


@pytest.mark.parametrize("use", OBJECT_USES)
def test_after_close_an_object_raises_world_closed_not_a_pybullet_error(
    use: Callable[[armfleet.WorldObject], object],
) -> None:
    world = armfleet.World()
    box = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(2, 0, 0.025))
    _ = box.pose  # measured once: a cached pose must not outlive the world either
    world.close()
    with pytest.raises(WorldClosed):
        use(box)
    assert box.name == "box" and box.size == (0.05, 0.05, 0.05)


@pytest.mark.parametrize("use", OBJECT_USES)
def test_after_remove_object_its_handle_raises_unknown_object(
    use: Callable[[armfleet.WorldObject], object],
) -> None:
    """As an arm's handle: UnknownObject listing the objects there are (not an ObjectError
    of its own), and WorldClosed first once the world is closed too."""
    with armfleet.World() as world:
        box = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(2, 0, 0.025))
        world.add_object("table", "box", size=(0.4, 0.4, 0.2), at=(3, 0, 0.1), mass=0)
        _ = box.pose  # measured once: a cached pose must not outlive the object
        world.remove_object("box")
        with pytest.raises(UnknownObject, match=r"^no object named 'box'; objects: table$"):
            use(box)
        assert box.name == "box" and box.size == (0.05, 0.05, 0.05) and box.removed
    with pytest.raises(WorldClosed):
        use(box)


def test_a_stale_object_handle_cannot_move_the_new_object_of_the_same_name() -> None:
    """box is removed and a new box added where the old one was: the old handle raises,
    the new box stays where it rests (within 1 mm: it settles on the floor)."""
    with armfleet.World() as world:
        old = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(2, 0, 0.025))
        world.remove_object("box")
        new = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(2, 0, 0.025))
        with pytest.raises(UnknownObject, match="no object named 'box'; objects: box"):
            old.set_pose((2, 0, 0.5))
        world.run(0.1)
        assert np.abs(new.position - (2, 0, 0.025)).max() < 1e-3  # [m]


@pytest.fixture
def removed() -> Iterator[tuple[armfleet.World, armfleet.Arm, armfleet.Gripper]]:
    """bob spawned, his gripper taken, then removed; toby stays."""
    with armfleet.World() as world:
        bob = world.spawn("bob")
        world.spawn("toby", at=(1, 0))
        gripper = bob.gripper
        world.remove("bob")
        yield world, bob, gripper


@pytest.mark.parametrize("use", ARM_USES)
def test_after_remove_every_use_of_the_arm_raises_unknown_arm(
    removed: tuple[armfleet.World, armfleet.Arm, armfleet.Gripper], use: Use
) -> None:
    world, bob, gripper = removed
    with pytest.raises(UnknownArm, match=r"no arm named 'bob'; arms: toby"):
        use(bob, world, gripper)
    still_readable(bob, gripper)


def test_a_stale_handle_cannot_move_the_new_arm_of_the_same_name(
    removed: tuple[armfleet.World, armfleet.Arm, armfleet.Gripper],
) -> None:
    """bob comes back; the old handle still raises, and the new bob does not move."""
    world, old_bob, old_gripper = removed
    new_bob = world.spawn("bob")
    commands: list[JointCommand | GripperCommand] = []
    world.bus.subscribe("/bob/position_controller/commands", commands.append)
    world.bus.subscribe("/bob/gripper_controller/commands", commands.append)
    before, width = new_bob.positions, new_bob.gripper.width
    target = before.copy()
    target[0] += 0.5
    with pytest.raises(UnknownArm):
        old_bob.move_to(target)
    with pytest.raises(UnknownArm):
        old_gripper.close()
    world.run(HOLD_CHECK_S)
    assert commands == []
    assert np.abs(new_bob.positions - before).max() < HOLD_DRIFT_RAD
    assert abs(new_bob.gripper.width - width) < 1e-4  # fingers still [m]
    assert new_bob.position_controller.is_holding
    assert new_bob.move_to(target) > 0  # the new handle works


def test_removing_one_arm_leaves_the_others_handles_working(
    removed: tuple[armfleet.World, armfleet.Arm, armfleet.Gripper],
) -> None:
    world, _, _ = removed
    toby = world.arm("toby")
    target = toby.positions
    target[0] += 0.2
    toby.move_to(target)
    toby.gripper.move_to(0.02)
    world.run(2.0)
    assert np.abs(toby.positions - target).max() < 1e-3  # arrived [rad]
    assert abs(toby.gripper.width - 0.02) < 1e-3  # [m]
    assert world.tf.lookup("world", "toby_tool0").shape == (4, 4)


def test_a_closed_world_is_named_before_a_removed_arm() -> None:
    """Removed, then the world closed: the closed world is what the user must fix first."""
    world = armfleet.World()
    bob = world.spawn("bob")
    world.remove("bob")
    world.close()
    with pytest.raises(WorldClosed):
        bob.move_to(np.zeros(7))
    assert isinstance(WorldClosed(), ArmfleetError)


def test_the_live_api_clients_handles_say_the_same(served: Served) -> None:  # noqa: F811
    """A client's handle of a removed arm gets the world's UnknownArm; after the client is
    closed its handles refuse in one line (a regression guard: this already held)."""
    world = served.world
    served.step_in_background()
    world.submit(lambda: world.spawn("toby", at=(1, 0))).result(timeout=60)
    client = armfleet.connect(served.server.address)
    try:
        bob, toby = client.arm("bob"), client.arm("toby")
        gripper = toby.gripper
        world.submit(lambda: world.remove("toby")).result(timeout=60)
        for use in (lambda: toby.move_to(np.zeros(7)), gripper.close, lambda: toby.positions):
            with pytest.raises(RemoteError) as caught:
                use()
            assert caught.value.kind == "UnknownArm"
            assert str(caught.value) == "no arm named 'toby'; arms: bob"
    finally:
        client.close()
    with pytest.raises(ArmfleetError, match="this client is closed"):
        bob.move_to(np.zeros(7))


#: What a handle *is*: readable after close. Everything else public must raise.
IDENTITY = {
    armfleet.Arm: {"name", "namespace", "model", "pose", "joint_names", "joint_limits",
                   "has_gripper", "description", "lifetime"},
    armfleet.Gripper: {"max_width", "min_width", "width_unit", "max_force", "force_unit",
                       "lifetime"},
    TfTree: {"lifetime"},
    armfleet.WorldObject: {"name", "shape", "size", "mass", "is_static", "friction", "color",
                           "mesh", "spec", "removed", "lifetime"},
}  # fmt: skip


def test_no_public_member_of_a_handle_escapes_the_check(
    closed: tuple[armfleet.World, armfleet.Arm, armfleet.Gripper],
) -> None:
    """A guard for members added later: every public method and property of Arm, Gripper,
    TfTree and WorldObject, called on a closed world's handle, raises WorldClosed, but for
    IDENTITY; and no handle has a public plain attribute, which no check could guard."""
    world, bob, gripper = closed
    with armfleet.World() as other:
        box = other.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(2, 0, 0.025))
    handles = {armfleet.Arm: bob, armfleet.Gripper: gripper, TfTree: world.tf,
               armfleet.WorldObject: box}  # fmt: skip
    for handle in handles.values():
        assert [name for name in vars(handle) if not name.startswith("_")] == []
    checked = []
    for cls, handle in handles.items():
        for name in dir(cls):
            member = inspect.getattr_static(cls, name)
            if name.startswith("_") or name in IDENTITY[cls]:
                continue
            if not isinstance(member, property | FunctionType):
                continue
            with pytest.raises(WorldClosed):
                value = getattr(handle, name)
                if isinstance(member, FunctionType):
                    value()  # the check comes before any argument is looked at
            checked.append(f"{cls.__name__}.{name}")
    assert {"Arm.move_to", "Arm.body", "Gripper.close", "TfTree.lookup",
            "WorldObject.set_pose", "WorldObject.body_id"} <= set(checked)  # fmt: skip
    for cls, handle in handles.items():
        for name in IDENTITY[cls]:
            getattr(handle, name)
