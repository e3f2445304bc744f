"""Every frame in a world has one owner (issue #14, items 6 and 11c).

Frames are compared with PyBullet's own link poses (``ArmBody.link_world_pose``,
read from the physics engine), not with the transform tree that is under test.
"""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.errors import FrameInUse
from armfleet.frames.frame_registry import FrameOwner, FrameRegistry
from armfleet.spec import SpecError, parse_spec

#: Two computations of one rigid frame (Pinocchio vs PyBullet, float64) agree to [m].
SAME_FRAME_M = 1e-9


def bodies(world: armfleet.World) -> int:
    return int(p.getNumBodies(physicsClientId=world.physics_client))


def test_an_xarm7_named_x_panda_beside_panda_x_is_refused(world: armfleet.World) -> None:
    x = world.spawn("x", "panda", (0, 0))
    before = bodies(world)
    with pytest.raises(FrameInUse) as raised:
        world.spawn("x_panda", "xarm7", (0, 3))
    assert raised.value.owner == "arm x" and raised.value.claimant == "arm x_panda"
    assert raised.value.frame.startswith("x_panda_")
    assert list(world.arms) == ["x"] and bodies(world) == before
    # The shared name means x's link: the goal frame of the issue reaches the right arm.
    np.testing.assert_allclose(
        world.tf.lookup("world", "x_panda_link1"),
        x.body.link_world_pose("x_panda_link1"),
        atol=SAME_FRAME_M,
    )


def test_an_object_named_like_a_future_arms_flange_keeps_its_frame(
    world: armfleet.World,
) -> None:
    box = world.add_object("carol_tool0", "box", size=(0.1, 0.1, 0.1), mass=0.0, at=(2, 2, 0.05))
    before = bodies(world)
    with pytest.raises(FrameInUse, match="which is object carol_tool0's already") as raised:
        world.spawn("carol", at=(0, 0))
    assert raised.value.frame == "carol_tool0" and raised.value.claimant == "arm carol"
    assert not world.arms and bodies(world) == before
    np.testing.assert_allclose(world.tf.lookup("world", "carol_tool0"), box.pose, atol=0)
    # Once the object is gone, its frame is free: carol comes up and owns its flange.
    world.remove_object("carol_tool0")
    carol = world.spawn("carol", at=(0, 0))
    # tool0 is a landmark, not a PyBullet link: PyBullet's hand and the fixed hand -> tool0.
    hand = carol.body.link_world_pose("carol_panda_hand")
    np.testing.assert_allclose(
        world.tf.lookup("world", "carol_tool0"),
        hand @ carol.kinematics.relative_pose("carol_panda_hand", "carol_tool0"),
        atol=1e-6,  # Pinocchio's model vs PyBullet's measured state, a settled arm
    )


def test_an_object_named_like_an_arms_frame_is_refused_naming_the_arm(
    world: armfleet.World,
) -> None:
    world.spawn("bob", at=(0, 0))
    for frame in ("bob_tool0", "bob_panda_joint4", "bob_base_link"):
        with pytest.raises(FrameInUse, match=f"object {frame} would own frame '{frame}', which"):
            world.add_object(frame, "sphere", size=0.05, at=(2, 0, 0.05))
    assert not world.objects


def test_removing_an_arm_frees_its_frames(world: armfleet.World) -> None:
    world.spawn("x", "panda", (0, 0))
    world.remove("x")
    xarm = world.spawn("x_panda", "xarm7", (0, 3))
    np.testing.assert_allclose(
        world.tf.lookup("world", "x_panda_link1"),
        xarm.body.link_world_pose("x_panda_link1"),
        atol=1e-6,
    )


def test_a_refused_object_leaves_no_claim_behind(world: armfleet.World) -> None:
    with pytest.raises(armfleet.ObjectError):
        world.add_object("tray", "box", size=(-1, 1, 1))
    world.add_object("tray", "box", size=(0.2, 0.2, 0.02), mass=0.0, at=(2, 0, 0.01))


def test_a_claim_is_all_or_nothing() -> None:
    registry = FrameRegistry()
    registry.claim(FrameOwner.arm("a"), ("a_link", "shared"))
    with pytest.raises(FrameInUse):
        registry.claim(FrameOwner.object("b"), ("b", "shared"))
    assert registry.owner("b") is None and registry.owner("shared") == FrameOwner.arm("a")
    registry.release(FrameOwner.arm("a"))
    registry.claim(FrameOwner.object("shared"), ("shared",))


BOB = "  - name: bob\n    model: panda\n    at_m: [0, 0]\n"


@pytest.mark.parametrize(
    ("text", "line", "says"),
    [
        pytest.param(
            "arms:\n" + BOB + "objects:\n  - name: bob_tool0\n    shape: sphere\n"
            "    size_m: 0.05\n    at_m: [2, 0, 0.05]\n",
            6,
            "objects[0].name: object bob_tool0 would own frame 'bob_tool0', which is arm bob's",
            id="object named like bob's flange -> refused at the object's name (11c)",
        ),
        pytest.param(
            "arms:\n  - name: x\n    model: panda\n  - name: x_panda\n    model: xarm7\n"
            "    at_m: [0, 3]\n",
            4,
            "arms[1].name: arm x_panda would own frame 'x_panda_joint1', which is arm x's",
            id="xarm7 x_panda after Panda x -> refused at the second arm's name",
        ),
    ],
)
def test_a_spec_check_refuses_a_second_owner(text: str, line: int, says: str) -> None:
    with pytest.raises(SpecError) as raised:
        parse_spec(text, "frames.yaml")
    assert raised.value.line == line
    assert says in str(raised.value)
