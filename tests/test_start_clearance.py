"""Would a new arm touch anything at its start pose? Asked before it enters (issue #14, item 7).

The reference is the physics engine itself, asked another way than the check
does: both bodies loaded with plain ``loadURDF`` into a fresh PyBullet client,
one collision detection pass, and the contact points between them
(``getContactPoints``, the points the simulation would act on). Accepted arms
are then held to what matters: nobody gets a protective stop.
"""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.arms.arm_assembly import start_positions
from armfleet.errors import (
    ArmfleetError,
    ObjectCollision,
    ObjectError,
    StartPoseCollision,
    UnknownFrame,
)
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.kinematics import ArmKinematics
from armfleet.objects import ObjectSpec, Shape, object_spec
from armfleet.objects.object_clearance import RESTING_OVERLAP_M
from armfleet.physics.start_clearance import CLEARANCE_M
from armfleet.spec import ArmSpec, FleetSpec, SpecError, parse_spec
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
    # The whole fleet is checked before the world starts: bob never came up.
    assert "[bob]" not in result.stdout and "ready" not in result.stdout, result.stdout


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
        pytest.param(
            "objects:\n  - name: box\n    shape: box\n    size_m: [0.1, 0.1, 0.1]\n"
            "    mass_kg: 0.5\n    at_m: [2, 0, 0.04]\n",
            "objects[0].at_m", 9, "it would overlap ground there (10.0 mm into it",
            id="a 0.5 kg box sunk 10 mm into the floor -> the object's at_m",
        ),
        pytest.param(
            "objects:\n  - name: table\n    shape: box\n    size_m: [0.6, 0.6, 0.4]\n"
            "    mass_kg: 0\n    at_m: [2, 0, 0.2]\n"
            "  - name: box\n    shape: box\n    size_m: [0.1, 0.1, 0.1]\n"
            "    at_m: [2, 0, 0.4]\n",
            "objects[1].at_m", 13, "it would overlap table there (50.0 mm into it",
            id="a box half into a static table -> the box's at_m",
        ),
    ],
)  # fmt: skip
def test_a_spec_points_at_the_line_to_change(extra: str, field: str, line: int, says: str) -> None:
    text = "arms:\n  - name: bob\n    model: panda\n" + extra
    with pytest.raises(SpecError) as raised:
        parse_spec(text, "cell.yaml")
    assert (raised.value.field, raised.value.line) == (field, line)
    assert says in raised.value.problem


# -- scene objects: the same question, asked of an object (objects/object_clearance.py) --
#: A 10 cm box, as the tests below place it [m].
SIDE_M = 0.1


def plain_box(client: int, at: Sequence[float], mass: float, side: float = SIDE_M) -> int:
    """A box as a plain PyBullet body (the reference: no armfleet code)."""
    shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[side / 2] * 3, physicsClientId=client)
    return int(p.createMultiBody(mass, shape, basePosition=list(at), physicsClientId=client))


@pytest.mark.parametrize("mass", [0.0, 0.5], ids=["static box", "0.5 kg box"])
def test_an_object_is_refused_exactly_when_the_physics_says_it_touches_an_arm(
    world: armfleet.World, physics: int, mass: float
) -> None:
    """A box slid along x through bob's hand; bob's hand must not be disturbed by it."""
    bob_arm = world.spawn("bob", at=(0, 0))
    bob = load_at_start(physics, world, "bob", SpawnPose())
    flange = world.tf.world_pose("bob_tool0")[:3, 3]
    bodies = p.getNumBodies(physicsClientId=world.physics_client)
    verdicts = {}
    for dx in (0.0, 0.05, 0.1, 0.15, 0.2, 0.3):
        at = flange + np.array([dx, 0.0, 0.0])
        box = plain_box(physics, at, mass)
        touching = deepest_contact_m(physics, bob, box) < CLEARANCE_M
        p.removeBody(box, physicsClientId=physics)
        if touching:
            with pytest.raises(ObjectCollision, match="it would touch bob there") as raised:
                world.add_object("box", "box", size=(SIDE_M,) * 3, mass=mass, at=at)
            assert raised.value.other == "bob" and raised.value.other_link.startswith("bob_")
            assert not world.objects
            assert p.getNumBodies(physicsClientId=world.physics_client) == bodies
            assert_nobody_stopped(world, 0)
        else:
            world.add_object("box", "box", size=(SIDE_M,) * 3, mass=mass, at=at)
            world.remove_object("box")
        verdicts[dx] = touching
    # Around the hand: refused (it used to stop bob, or fling the box and bob's joints).
    assert verdicts[0.0] and not verdicts[0.3]
    assert bob_arm.status(world.time).mode is armfleet.ArmMode.HOLDING


Placed = tuple[str, float, tuple[float, float, float], tuple[float, float, float]]


def placed(name: str, mass: float, size: Sequence[float], at: Sequence[float]) -> Placed:
    """(name, mass [kg], box size [m], centre [m])."""
    return name, mass, (size[0], size[1], size[2]), (at[0], at[1], at[2])


CUBE = (SIDE_M,) * 3
TABLE = placed("table", 0.0, (0.6, 0.6, 0.4), (0, 0, 0.2))
LOW = placed("low", 0.5, CUBE, (0, 0, 0.05))  # a 0.5 kg box on the floor


@pytest.mark.parametrize(
    ("before", "new"),
    [
        pytest.param((), placed("box", 0.5, CUBE, (0, 0, 0.05)),
                     id="a 0.5 kg box resting on the floor -> added, stays put"),
        pytest.param((), placed("box", 0.5, CUBE, (0, 0, 0.049)),
                     id="a 0.5 kg box 1 mm into the floor -> added, moved out by 1 mm"),
        pytest.param((TABLE,), placed("box", 0.5, CUBE, (0, 0, 0.45)),
                     id="a 0.5 kg box on a static table -> added, stays put"),
        pytest.param((LOW,), placed("box", 0.5, CUBE, (0, 0, 0.15)),
                     id="a 0.5 kg box stacked on another -> added, both stay put"),
        pytest.param((placed("top", 0.0, (0.6, 0.6, 0.04), (0, 0, 0.4)),),
                     placed("leg", 0.0, (0.05, 0.05, 0.4), (0.25, 0.25, 0.2)),
                     id="a static leg 2 cm into a static table top -> added, neither ever moves"),
        pytest.param((), placed("platform", 0.0, (1, 1, 0.2), (0, 0, 0)),
                     id="a static platform half under the floor -> added, neither ever moves"),
    ],
)  # fmt: skip
def test_an_object_may_rest_on_the_floor_or_an_object(
    world: armfleet.World, before: Sequence[Placed], new: Placed
) -> None:
    for name, mass, size, at in (*before, new):
        world.add_object(name, "box", size=size, mass=mass, at=at)
    world.run(0.5)
    for name, _, _, at in (*before, new):
        moved = np.linalg.norm(world.object(name).position - np.array(at))
        # Resting: moved by no more than it was allowed to sink (the solver pushes it out).
        assert moved < RESTING_OVERLAP_M, (name, moved)


@pytest.mark.parametrize(
    ("before", "new", "other"),
    [
        pytest.param((), placed("box", 0.5, CUBE, (0, 0, 0.04)), "ground",
                     id="a 0.5 kg box 10 mm into the floor -> ObjectCollision naming ground"),
        pytest.param((TABLE,), placed("box", 0.5, CUBE, (0, 0, 0.4)), "table",
                     id="a 0.5 kg box half into a static table -> ObjectCollision naming it"),
        pytest.param((LOW,), placed("box", 0.0, CUBE, (0.05, 0, 0.05)),
                     "low", id="a static box into a 0.5 kg box -> ObjectCollision naming it"),
        pytest.param((LOW,), placed("box", 0.5, CUBE, (0, 0, 0.12)),
                     "low", id="a 0.5 kg box 3 cm into another -> ObjectCollision naming it"),
    ],
)  # fmt: skip
def test_an_object_that_would_be_thrown_out_of_an_overlap_is_refused(
    world: armfleet.World, physics: int, before: Sequence[Placed], new: Placed, other: str
) -> None:
    for name, mass, size, at in before:
        world.add_object(name, "box", size=size, mass=mass, at=at)
    bodies = p.getNumBodies(physicsClientId=world.physics_client)
    name, mass, size, at = new
    with pytest.raises(ObjectCollision, match=f"it would overlap {other} there") as raised:
        world.add_object(name, "box", size=size, mass=mass, at=at)
    assert raised.value.distance_m < -RESTING_OVERLAP_M and raised.value.other == other
    assert list(world.objects) == [b[0] for b in before]
    assert p.getNumBodies(physicsClientId=world.physics_client) == bodies


def test_a_moving_mesh_placed_exactly_on_the_floor_is_resting(
    world: armfleet.World, tmp_path: Path
) -> None:
    """A moving mesh collides as its convex hull, 1 mm of margin included: placed with its
    bottom face on the floor it overlaps it by that 1 mm, and must still be accepted."""
    corners = [(x, y, z) for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (0.0, 0.1)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    cube = tmp_path / "cube.obj"
    cube.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in corners)
        + "".join(f"f {a} {b} {c}\nf {a} {c} {d}\n" for a, b, c, d in faces)
    )
    mug = world.add_object("mug", "mesh", mesh=cube, mass=0.5, at=(0, 0, 0))
    world.run(0.5)
    assert np.linalg.norm(mug.position) < RESTING_OVERLAP_M  # pushed out by its margin only


# -- a FleetSpec built in Python goes through the same check as a spec file ------------------
MITT = object_spec("mitt", "box", size=CUBE, mass=0.0, at=(0.307, 0.0, 0.59))  # bob's hand


def box_spec(name: str, mass: float, at: Sequence[float]) -> ObjectSpec:
    return object_spec(name, "box", size=CUBE, mass=mass, at=at)


@pytest.mark.parametrize(
    ("spec", "error", "says"),
    [
        pytest.param(
            FleetSpec(arms=(ArmSpec("bob"), ArmSpec("toby", pose=SpawnPose(0.3, 0.0)))),
            StartPoseCollision, "toby would touch bob at its start pose",
            id="Pandas 0.3 m apart -> StartPoseCollision, no world",
        ),
        pytest.param(
            FleetSpec(arms=(ArmSpec("bob"),), objects=(MITT,)),
            StartPoseCollision, "bob would touch mitt at its start pose",
            id="a static box in bob's hand -> StartPoseCollision, no world",
        ),
        pytest.param(
            FleetSpec(
                arms=(ArmSpec("bob"),),
                objects=(box_spec("crate", 0.0, (2, 0, 0.05)), box_spec("cup", 0.5, (2, 0, 0.1))),
            ),
            ObjectCollision, "object 'cup': at: it would overlap crate there",
            id="a 0.5 kg box half into a static one -> ObjectCollision, no world",
        ),
        pytest.param(
            FleetSpec(
                arms=(ArmSpec("bob"),),
                objects=(ObjectSpec("box", Shape.BOX, (-0.1, 0.1, 0.1), at=(2.0, 0.0, 0.5)),),
            ),
            ObjectError, "object 'box': size: [-0.1, 0.1, 0.1]: each must be in (0, 100] m",
            id="an ObjectSpec built by hand with a negative size -> ObjectError, no world",
        ),
        pytest.param(
            FleetSpec(arms=(ArmSpec("bob"), ArmSpec("bob", pose=SpawnPose(3.0, 0.0)))),
            ArmfleetError, "'bob'",
            id="one name twice -> the world's name error, no world",
        ),
    ],
)  # fmt: skip
def test_a_fleet_spec_from_python_is_checked_before_its_world_exists(
    spec: FleetSpec, error: type[ArmfleetError], says: str
) -> None:
    worlds: list[armfleet.World] = []
    with pytest.raises(error, match=re.escape(says)):
        armfleet.launch(spec, viewer=False, before_spawn=worlds.append)
    assert not worlds  # no world was created: nothing came up, nothing was recorded


@pytest.mark.parametrize("mass", [0.0, 0.5], ids=["static box", "0.5 kg box"])
def test_an_arm_and_an_object_get_one_verdict_whichever_comes_first(mass: float) -> None:
    """What lets a spec's check (objects, then arms) agree with launch (arms, then objects)."""
    verdicts: dict[str, list[bool]] = {"object last": [], "arm last": []}
    with armfleet.World() as arm_first, armfleet.World() as object_first:
        arm_first.spawn("bob", at=(0, 0))
        flange = arm_first.tf.world_pose("bob_tool0")[:3, 3]
        for dx in (0.0, 0.1, 0.13, 0.14, 0.15, 0.16, 0.2, 0.3):
            at = tuple(flange + np.array([dx, 0.0, 0.0]))
            try:
                arm_first.add_object("box", "box", size=CUBE, mass=mass, at=at)
                arm_first.remove_object("box")
                verdicts["object last"].append(True)
            except ObjectCollision:
                verdicts["object last"].append(False)
            object_first.add_object("box", "box", size=CUBE, mass=mass, at=at)
            try:
                object_first.spawn("bob", at=(0, 0))
                object_first.remove("bob")
                verdicts["arm last"].append(True)
            except StartPoseCollision:
                verdicts["arm last"].append(False)
            object_first.remove_object("box")
    assert verdicts["object last"] == verdicts["arm last"]
    assert True in verdicts["arm last"] and False in verdicts["arm last"]


@pytest.mark.parametrize("overlap_m", [0.0, 1e-3, RESTING_OVERLAP_M, 10e-3])
def test_the_solver_only_pushes_a_resting_overlap_out_and_throws_a_deeper_one(
    physics: int, overlap_m: float
) -> None:
    """Plain PyBullet, no armfleet: a 0.5 kg box released ``overlap_m`` into the floor."""
    p.setGravity(0, 0, -9.81, physicsClientId=physics)
    p.setTimeStep(0.001, physicsClientId=physics)
    floor = p.createCollisionShape(p.GEOM_BOX, halfExtents=[5, 5, 0.5], physicsClientId=physics)
    p.createMultiBody(0.0, floor, basePosition=[0, 0, -0.5], physicsClientId=physics)
    start = SIDE_M / 2 - overlap_m
    box = plain_box(physics, (0.0, 0.0, start), 0.5)
    highest = start
    for _ in range(500):
        p.stepSimulation(physicsClientId=physics)
        z = p.getBasePositionAndOrientation(box, physicsClientId=physics)[0][2]
        highest = max(highest, z)
    rise = highest - start
    if overlap_m <= RESTING_OVERLAP_M:
        assert rise <= overlap_m + 1e-4  # out by the overlap, 0.1 mm of slack, no more
    else:
        assert rise > 2 * overlap_m  # thrown (measured: 33 mm for 10 mm)


def test_a_clear_fleet_spec_from_python_comes_up_whole() -> None:
    """The check refuses nothing the world accepts: poses as plain tuples (which spawn
    takes), a table under one arm's base, a box resting on the table beside it, a box on
    the floor."""
    spec = FleetSpec(
        arms=(
            ArmSpec("bob", pose=(0.0, 0.0, 0.4)),  # type: ignore[arg-type]
            ArmSpec("toby", pose=SpawnPose(1.2, 0.0, 0.0, 180.0)),
        ),
        objects=(
            object_spec("table", "box", size=(0.4, 0.4, 0.4), mass=0.0, at=(0, 0, 0.2)),
            box_spec("cube", 0.5, (0.0, 1.0, 0.05)),
            box_spec("cup", 0.5, (-0.14, 0.14, 0.45)),  # beside bob's base
        ),
    )
    world = armfleet.launch(spec, viewer=False)
    try:
        assert list(world.arms) == ["bob", "toby"]
        assert list(world.objects) == ["table", "cube", "cup"]
        assert_nobody_stopped(world, 0)
    finally:
        world.close()


@pytest.mark.parametrize("mass", [0.0, 0.5], ids=["static box", "0.5 kg box"])
def test_teleporting_an_object_into_an_arm_is_refused_and_it_stays_put(
    world: armfleet.World, physics: int, mass: float
) -> None:
    """set_pose is the same question as add_object: would it touch the arm where it goes?"""
    world.spawn("bob", at=(0, 0))
    box = world.add_object("box", "box", size=(0.1, 0.1, 0.1), mass=mass, at=(1.0, 0, 0.05))
    hand = world.tf.world_pose("bob_tool0")[:3, 3].tolist()
    # The physics' own answer, in a client of its own: a plain box at the hand touches bob.
    reference_bob = load_at_start(physics, world, "bob", SpawnPose())
    reference_box = plain_box(physics, hand, mass, 0.1)
    assert deepest_contact_m(physics, reference_bob, reference_box) < CLEARANCE_M
    before = box.pose
    with pytest.raises(ObjectCollision, match=r"would touch bob there.*it was not moved"):
        box.set_pose(hand)
    assert np.array_equal(box.pose, before)
    assert_nobody_stopped(world, 0)
    box.set_pose((1.0, 0.5, 0.05))  # clear of everything: taken
    assert np.allclose(box.pose[:3, 3], (1.0, 0.5, 0.05), atol=1e-3)


def test_removing_an_object_through_its_handle_frees_its_name_and_frame(
    world: armfleet.World,
) -> None:
    """obj.remove() is the world's removal: a new object may take the name and its frame."""
    box = world.add_object("box", "box", size=(0.1, 0.1, 0.1), mass=0.5, at=(1.0, 0, 0.05))
    body = box.spec
    box.remove()
    assert "box" not in world.objects
    with pytest.raises(UnknownFrame):
        world.tf.world_pose("box")
    again = world.add_object("box", "box", size=(0.1, 0.1, 0.1), mass=0.5, at=(1.0, 0, 0.05))
    assert again.spec == body
    world.run(0.2)  # the contact monitor knows only the new body
    assert world.safety.stops == 0
