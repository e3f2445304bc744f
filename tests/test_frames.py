"""Invariant 1: every link's world pose agrees between PyBullet, Pinocchio and TF to 1e-6."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.messages import TFMessage

POSE_TOLERANCE = 1e-6
SPAWN_POSES = [
    (0.0, 0.0),
    (1.0, -0.5, 0.0, 90.0),
    (-0.7, 0.4, 0.3, 0.0),
    (0.25, 2.0, 0.3, -135.0),
    armfleet.SpawnPose(0.5, -1.0, 1.0, 45.0, roll_deg=90.0, pitch_deg=10.0),  # wall mount
]


def pose_id(at: object) -> str:
    return "at" + str(armfleet.SpawnPose.from_values(at)).replace(" ", "")  # type: ignore[arg-type]


def random_configuration(arm: armfleet.Arm, seed: int) -> np.ndarray:
    lower, upper = arm.joint_limits
    rng = np.random.default_rng(seed)
    return lower + (upper - lower) * rng.uniform(0.1, 0.9, size=lower.size)


def move_to_random_configuration(arm: armfleet.Arm, seed: int) -> None:
    """Send ``arm`` to a random configuration it reaches without touching itself (move_to
    refuses the others), drawn from ``seed`` on."""
    for attempt in range(50):
        try:
            arm.move_to(random_configuration(arm, seed=1000 * attempt + seed))
            return
        except armfleet.SelfContactError:
            continue
    raise AssertionError(f"no random configuration of {arm.name} clear of itself in 50 draws")


@pytest.mark.parametrize("model", ["panda", "ur5"])
@pytest.mark.parametrize("at", SPAWN_POSES, ids=pose_id)
def test_link_poses_agree(model: str, at: tuple[float, ...]) -> None:
    with armfleet.World() as world:
        arm = world.spawn("bob", model=model, at=at)
        move_to_random_configuration(arm, seed=SPAWN_POSES.index(at))
        world.run(0.3)  # mid-motion, joints away from home and moving
        assert arm.is_moving
        links = arm.body.link_names
        assert len(links) >= 8
        arm.kinematics.update(arm.body.position)
        for link in links:
            from_bullet = arm.body.link_world_pose(link)
            from_pinocchio = arm.kinematics.world_pose(link)
            from_tf = world.tf.lookup("world", link)
            assert np.abs(from_bullet - from_pinocchio).max() < POSE_TOLERANCE, link
            assert np.abs(from_tf - from_pinocchio).max() < POSE_TOLERANCE, link


@pytest.mark.parametrize("at", SPAWN_POSES, ids=pose_id)
def test_static_transform_carries_the_spawn_pose(world: armfleet.World, at) -> None:
    statics: list[TFMessage] = []
    world.bus.subscribe("/tf_static", statics.append)
    world.spawn("bob", at=at)
    expected = armfleet.SpawnPose.from_values(at).matrix()
    base = [
        t
        for m in statics
        for t in m.transforms
        if (t.frame_id, t.child_frame_id) == ("world", "bob_base_link")
    ]
    assert len(base) == 1
    assert np.abs(base[0].matrix - expected).max() < 1e-12
    assert np.abs(world.tf.lookup("world", "bob_base_link") - expected).max() < 1e-12


def test_tf_static_is_latched_for_late_subscribers(pair: armfleet.World) -> None:
    late: list[TFMessage] = []
    pair.bus.subscribe("/tf_static", late.append)
    children = {t.child_frame_id for m in late for t in m.transforms}
    assert {"bob_base_link", "toby_base_link", "bob_tool0", "toby_tool0"} <= children


def test_tf_chain_composes_to_the_world_pose(pair: armfleet.World) -> None:
    """Composing /tf_static and /tf edges from world reproduces every link pose."""
    edges: dict[str, tuple[str, np.ndarray]] = {}

    def collect(message: TFMessage) -> None:
        for t in message.transforms:
            edges[t.child_frame_id] = (t.frame_id, t.matrix)

    pair.bus.subscribe("/tf_static", collect)
    pair.bus.subscribe("/tf", collect)
    toby = pair.arm("toby")
    toby.move_to(random_configuration(toby, seed=3))
    pair.run(0.25)

    def composed(frame: str) -> np.ndarray:
        if frame == "world":
            return np.eye(4)
        parent, matrix = edges[frame]
        result: np.ndarray = composed(parent) @ matrix
        return result

    # /tf carries the state of the last published joint_states, read before the last step.
    toby.kinematics.update(toby.joint_state.position)
    for link in toby.body.link_names:
        expected = toby.kinematics.world_pose(link)
        assert np.abs(composed(link) - expected).max() < POSE_TOLERANCE, link


def test_lookup_between_two_arms(pair: armfleet.World) -> None:
    bob_tool = pair.tf.lookup("world", "bob_tool0")
    toby_tool = pair.tf.lookup("world", "toby_tool0")
    relative = pair.tf.lookup("bob_tool0", "toby_tool0")
    assert np.abs(bob_tool @ relative - toby_tool).max() < 1e-12
    # toby stands 1 m along x from bob in the same home pose, both holding it to
    # within the hold tolerance (1e-3 rad), so the flanges are 1 m apart to < 1 mm.
    assert np.abs(relative[:3, 3] - bob_tool[:3, :3].T @ np.array([1.0, 0, 0])).max() < 1e-3


def test_unknown_frame_names_the_choices(pair: armfleet.World) -> None:
    with pytest.raises(armfleet.ArmfleetError, match="arms: bob, toby"):
        pair.tf.lookup("world", "carol_tool0")


@pytest.mark.parametrize("model", ["panda", "ur5"])
def test_pybullet_and_pinocchio_dynamics_agree(model: str) -> None:
    """With inertias from the file, PyBullet's inverse dynamics equals Pinocchio's RNEA."""
    with armfleet.World() as world:
        arm = world.spawn("bob", model=model, at=(0.3, 0.2, 0.1, 30))
        rng = np.random.default_rng(7)
        n = arm.kinematics.model.nq
        lower, upper = arm.kinematics.lower, arm.kinematics.upper
        for _ in range(5):
            q = lower + (upper - lower) * rng.uniform(0.1, 0.9, n)
            v, a = rng.normal(size=n), rng.normal(size=n)
            from_bullet = np.array(
                p.calculateInverseDynamics(
                    arm.body.body_id,
                    q.tolist(),
                    v.tolist(),
                    a.tolist(),
                    physicsClientId=world.physics_client,
                )
            )
            # PyBullet's inverse dynamics leaves out joint damping; RNEA alone matches it.
            from_pinocchio = arm.kinematics.inverse_dynamics(q, v, a) - arm.kinematics.damping * v
            assert np.abs(from_bullet - from_pinocchio).max() < 1e-8
