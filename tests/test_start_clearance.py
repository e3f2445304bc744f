"""Would a new arm touch anything at its start pose? Asked before it enters (issue #14, item 7).

The reference is the physics engine itself, asked another way than the check
does: both bodies loaded with plain ``loadURDF`` into a fresh PyBullet client,
one collision detection pass, and the contact points between them
(``getContactPoints``, the points the simulation would act on). Accepted arms
are then held to what matters: nobody gets a protective stop.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.arm_assembly import start_positions
from armfleet.errors import StartPoseCollision
from armfleet.kinematics import ArmKinematics
from armfleet.spawn_pose import SpawnPose
from armfleet.spec import SpecError, parse_spec
from armfleet.start_clearance import CLEARANCE_M
from tests.remote_world import ARMFLEET, runtime_env

#: A settled arm's joints drift less than this over the checks' 0.3 s [rad].
HOLD_DRIFT_RAD = 1e-4


@pytest.fixture
def physics() -> Iterator[int]:
    """A fresh PyBullet client for the reference computations."""
    client = p.connect(p.DIRECT)
    yield client
    p.disconnect(physicsClientId=client)


def load_at_start(
    client: int,
    world: armfleet.World,
    name: str,
    pose: SpawnPose,
    initial: Sequence[float] | None = None,
    flags: int = 0,
) -> int:
    """The arm ``name`` as a plain PyBullet body at its start configuration."""
    description = world.models.expand("panda", f"{name}_", pose)
    kinematics = ArmKinematics(description.urdf, description.tool0)
    start = start_positions(name, kinematics, description.home, initial)
    fd, path = tempfile.mkstemp(suffix=".urdf")
    with os.fdopen(fd, "w") as file:
        file.write(description.urdf)
    try:
        body = p.loadURDF(path, useFixedBase=True, flags=flags, physicsClientId=client)
    finally:
        os.unlink(path)
    joints = {
        p.getJointInfo(body, i, physicsClientId=client)[1].decode(): i
        for i in range(p.getNumJoints(body, physicsClientId=client))
    }
    for joint, value in zip(kinematics.joint_names, start, strict=True):
        p.resetJointState(body, joints[joint], float(value), physicsClientId=client)
    return int(body)


def deepest_contact_m(client: int, a: int, b: int) -> float:
    """Smallest signed distance [m] of the contact points between bodies a and b (inf: none)."""
    p.performCollisionDetection(physicsClientId=client)
    points = p.getContactPoints(bodyA=a, bodyB=b, physicsClientId=client)
    return min((point[8] for point in points), default=np.inf)


def assert_nobody_stopped(world: armfleet.World, stops: int) -> None:
    held = {name: arm.positions for name, arm in world.arms.items()}
    world.run(0.3)
    assert world.safety.stops == stops
    for name, arm in world.arms.items():
        assert arm.status(world.time).mode is armfleet.ArmMode.HOLDING, name
        assert np.max(np.abs(arm.positions - held[name])) < HOLD_DRIFT_RAD, name


@pytest.mark.parametrize("yaw_deg", [0.0, 180.0])
def test_a_neighbour_is_refused_exactly_when_the_physics_says_they_touch(
    world: armfleet.World, physics: int, yaw_deg: float
) -> None:
    """Two Pandas in a row, toby at x = d; bob's hand points at toby's base."""
    world.spawn("bob", at=(0, 0))
    bob = load_at_start(physics, world, "bob", SpawnPose())
    verdicts = {}
    for d in (0.0, 0.1, 0.3, 0.45, 0.55, 0.6, 0.75, 1.0):
        pose = SpawnPose(d, 0.0, 0.0, yaw_deg)
        toby = load_at_start(physics, world, "toby", pose)
        touching = deepest_contact_m(physics, bob, toby) < CLEARANCE_M
        p.removeBody(toby, physicsClientId=physics)
        stops = world.safety.stops
        if touching:
            with pytest.raises(StartPoseCollision, match="toby would touch bob at its start pose"):
                world.spawn("toby", at=pose)
            assert list(world.arms) == ["bob"]
            assert_nobody_stopped(world, stops)
        else:
            world.spawn("toby", at=pose)
            assert_nobody_stopped(world, stops)
            world.remove("toby")
        verdicts[d] = touching
    # The old 0.25 m rule passed 0.3 m; at home two Pandas touch up to about 0.55 m.
    assert verdicts[0.3] and verdicts[0.45] and not verdicts[1.0]


def test_a_refused_spawn_does_not_stop_a_neighbour_mid_motion(world: armfleet.World) -> None:
    bob = world.spawn("bob", at=(0, 0))
    target = bob.positions
    target[0] += 0.6
    bob.move_to(target)
    world.run(0.2)
    assert bob.is_moving
    with pytest.raises(StartPoseCollision, match="toby would touch bob"):
        world.spawn("toby", at=(0.3, 0))
    world.run(3.0)
    assert world.safety.stops == 0
    assert np.max(np.abs(bob.positions - target)) < 1e-3  # arrived: hold tolerance [rad]


#: joint4 at its lower limit (elbow shut) folds the Panda's hand into its link1.
FOLDED = (0.0, 0.3, 0.0, -3.0718, 0.0, 1.57, 0.7854)


def test_an_arm_folded_into_itself_is_refused(world: armfleet.World, physics: int) -> None:
    flags = p.URDF_USE_SELF_COLLISION | p.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT
    toby = load_at_start(physics, world, "toby", SpawnPose(), FOLDED, flags)
    with pytest.raises(StartPoseCollision, match="toby would touch itself") as raised:
        world.spawn("toby", initial_positions=FOLDED)
    error = raised.value
    links = {
        p.getJointInfo(toby, i, physicsClientId=physics)[12].decode(): i
        for i in range(p.getNumJoints(toby, physicsClientId=physics))
    }
    p.performCollisionDetection(physicsClientId=physics)
    points = p.getContactPoints(
        toby, toby, links[error.link], links[error.other_link], physicsClientId=physics
    )
    assert points and min(point[8] for point in points) < 0.0  # the named links overlap
    assert error.distance_m < 0.0 and not world.arms


def test_a_joint_exactly_at_its_limit_with_nothing_touching_comes_up(
    world: armfleet.World,
) -> None:
    """What bring-up rejects is contact, not a joint on its limit (measured: every joint of
    panda, ur5, xarm7 and z1 at each limit, others at home, held once nothing touched)."""
    home = (0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398)
    for index, limit in ((3, -0.0698), (5, 3.7525), (0, -2.8973)):
        initial = list(home)
        initial[index] = limit
        arm = world.spawn("toby", at=(0, 0), initial_positions=initial)
        assert abs(arm.positions[index] - limit) < 1e-3  # held there: hold tolerance [rad]
        assert world.safety.stops == 0
        world.remove("toby")


def test_sunk_into_the_floor_is_refused_standing_on_it_is_not(world: armfleet.World) -> None:
    with pytest.raises(StartPoseCollision, match="toby would touch ground"):
        world.spawn("toby", at=(0, 0, -0.2))
    world.spawn("toby", at=(0, 0, 0))  # the base rests on the floor: not a contact
    assert world.safety.stops == 0


def test_standing_on_a_table_is_clear_a_box_in_the_arm_is_not(world: armfleet.World) -> None:
    world.add_object("table", "box", size=(0.6, 0.6, 0.4), mass=0.0, at=(0, 0, 0.2))
    world.add_object("crate", "box", size=(0.2, 0.2, 0.2), mass=0.5, at=(3.3, 0, 0.5))
    bob = world.spawn("bob", at=(0, 0, 0.4))  # on the table: its base may rest there
    with pytest.raises(StartPoseCollision, match="toby would touch crate"):
        world.spawn("toby", at=(3, 0))
    assert list(world.arms) == ["bob"]
    assert_nobody_stopped(world, 0)
    assert bob.status(world.time).mode is armfleet.ArmMode.HOLDING


def test_a_new_world_from_the_cli_refuses_touching_arms(tmp_path: Path) -> None:
    result = subprocess.run(
        [*ARMFLEET, "spawn", "bob", "toby", "--at", "0,0", "0.3,0", "--new-world",
         "--no-viewer", "--duration", "0.1"],
        capture_output=True, text=True, env=runtime_env(tmp_path), timeout=120,
    )  # fmt: skip
    assert result.returncode == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert "toby would touch bob at its start pose" in lines[0]


@pytest.mark.parametrize(
    ("extra", "field", "line", "says"),
    [
        pytest.param(
            "  - name: toby\n    model: panda\n    at_m: [0.3, 0]\n",
            "arms[1].at_m", 6, "toby would touch bob",
            id="touching a neighbour -> the arm's at_m",
        ),
        pytest.param(
            f"  - name: toby\n    model: panda\n    at_m: [3, 0]\n"
            f"    initial_positions: {list(FOLDED)}\n",
            "arms[1].initial_positions", 7, "toby would touch itself",
            id="folded into itself -> the arm's initial_positions",
        ),
    ],
)  # fmt: skip
def test_a_spec_points_at_the_line_to_change(extra: str, field: str, line: int, says: str) -> None:
    text = "arms:\n  - name: bob\n    model: panda\n" + extra
    with pytest.raises(SpecError) as raised:
        parse_spec(text, "cell.yaml")
    assert (raised.value.field, raised.value.line) == (field, line)
    assert says in raised.value.problem
