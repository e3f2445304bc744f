"""Scene objects: physics, frames on /tf and /tf_static, contacts, safety, removal, bad input."""

from __future__ import annotations

import math
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.messages import ArmMode, CollisionReport, TFMessage

#: A body resting on another sinks into it by PyBullet's contact slop; well under this [m].
REST_TOLERANCE_M = 1e-3
TABLE_TOP_M = 0.4


def add_table(world: armfleet.World, at: tuple[float, float] = (0.6, 0.0)) -> armfleet.WorldObject:
    """A static 0.6 x 0.8 x 0.4 m table whose top is at z = 0.4 m."""
    return world.add_object(
        "table",
        "box",
        size=(0.6, 0.8, TABLE_TOP_M),
        mass=0,
        color=(0.6, 0.45, 0.3, 1),
        at=(*at, TABLE_TOP_M / 2),
    )


def run_until_still(world: armfleet.World, obj: armfleet.WorldObject, limit_s: float = 3.0) -> None:
    """Step until ``obj`` moves slower than 1 mm/s (after at least 0.2 s)."""
    world.run(0.2)
    while np.linalg.norm(obj.velocity) > 1e-3 and limit_s > 0:
        world.run(0.1)
        limit_s -= 0.1


def test_box_dropped_on_a_table_rests_on_its_top(world: armfleet.World) -> None:
    table = add_table(world)
    box = world.add_object(
        "box", "box", size=(0.05, 0.05, 0.05), mass=0.2, at=(0.6, 0.1, 0.7), rpy_deg=(0, 0, 30)
    )
    assert table.is_static and not box.is_static
    run_until_still(world, box)
    assert abs(box.position[2] - (TABLE_TOP_M + 0.025)) < REST_TOLERANCE_M
    assert np.abs(box.position[:2] - (0.6, 0.1)).max() < REST_TOLERANCE_M, "fell straight down"
    yaw = math.degrees(math.atan2(box.pose[1, 0], box.pose[0, 0]))
    assert abs(yaw - 30.0) < 0.5, "landed flat, still turned 30 deg"
    assert np.abs(table.position - (0.6, 0.0, 0.2)).max() < 1e-12, "the table never moves"
    assert np.abs(world.tf.lookup("world", "box") - box.pose).max() < 1e-12
    on_table = world.tf.lookup("table", "box")
    assert abs(on_table[2, 3] - (TABLE_TOP_M / 2 + 0.025)) < REST_TOLERANCE_M


@pytest.mark.parametrize(
    ("shape", "size", "rest_z"),
    [("cylinder", (0.03, 0.12), 0.06), ("sphere", 0.04, 0.04), ("box", (0.1, 0.2, 0.3), 0.15)],
)
def test_shapes_rest_on_the_ground_at_their_size(
    world: armfleet.World, shape: str, size: object, rest_z: float
) -> None:
    obj = world.add_object("thing", shape, size=size, at=(0.0, 0.0, rest_z + 0.05))  # type: ignore[arg-type]
    run_until_still(world, obj)
    assert abs(obj.position[2] - rest_z) < REST_TOLERANCE_M
    assert abs(obj.pose[2, 2] - 1.0) < 1e-3, "still upright: the cylinder's axis is its z"


@pytest.mark.parametrize(("friction", "slides"), [(0.8, False), (0.1, True)])
def test_friction_holds_a_box_on_a_ramp_or_lets_it_slide(
    world: armfleet.World, friction: float, slides: bool
) -> None:
    # A 20 deg ramp: tan 20 deg = 0.36. Bullet multiplies both bodies' coefficients:
    # 0.8 * 0.8 = 0.64 holds the box, 0.1 * 0.8 = 0.08 does not.
    world.add_object(
        "ramp", "box", size=(1.0, 0.4, 0.02), mass=0, at=(0, 0, 0.3), rpy_deg=(0, 20, 0)
    )
    ramp = world.object("ramp").pose
    start = ramp[:3, 3] + ramp[:3, 2] * (0.01 + 0.025 + 1e-4)
    pitch = (0, 20, 0)
    box = world.add_object(
        "box", "box", size=(0.05, 0.05, 0.05), friction=friction, at=tuple(start), rpy_deg=pitch
    )
    world.run(0.5)
    moved = float(np.linalg.norm(box.position - start))
    if slides:
        assert moved > 0.1, f"moved only {moved:.4f} m down a slippery ramp"
    else:
        assert moved < 2e-3, f"slid {moved:.4f} m although friction holds it"


def test_object_frames_on_tf_and_tf_static(world: armfleet.World) -> None:
    add_table(world)
    box = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(0.6, 0.0, 0.6))
    (latched,) = [
        t
        for m in world.bus.latched("/tf_static")
        for t in m.transforms
        if t.child_frame_id == "table"
    ]
    assert latched.frame_id == "world"
    assert np.abs(latched.matrix[:3, 3] - (0.6, 0.0, 0.2)).max() < 1e-12
    seen: list[TFMessage] = []
    subscription = world.bus.subscribe("/tf", seen.append)
    world.run(0.01)
    subscription.cancel()
    assert len(seen) == 10, "one /tf message per step for the moving objects"
    last = seen[-1].transforms
    assert [(t.frame_id, t.child_frame_id) for t in last] == [("world", "box")]
    assert np.abs(last[0].matrix - box.pose).max() < 1e-12
    assert last[0].stamp == pytest.approx(world.time)


def test_removed_object_leaves_tf_contacts_and_the_world(world: armfleet.World) -> None:
    table = add_table(world)
    box = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(0.6, 0.0, 0.4251))
    reports: list[CollisionReport] = []
    world.bus.subscribe("/collisions", reports.append)
    world.run(0.05)
    bodies = {(c.body_a, c.body_b) for c in reports[-1].contacts}
    assert bodies & {("box", "table"), ("table", "box")}, bodies
    assert all(c.link_a == c.link_b == "" for c in reports[-1].contacts)
    body_id = box.body_id

    world.remove_object("box")
    world.remove_object("table")
    assert world.objects == {} and box.removed and table.removed
    assert p.getNumBodies(physicsClientId=world.physics_client) == 1, "only the ground is left"
    with pytest.raises(armfleet.UnknownObject, match="no object named 'box'; objects: \\(none\\)"):
        world.object("box")
    with pytest.raises(armfleet.ArmfleetError, match="frame 'box' not found"):
        world.tf.lookup("world", "box")
    assert not [m for m in world.bus.latched("/tf_static") for t in m.transforms]
    seen: list[TFMessage] = []
    world.bus.subscribe("/tf", seen.append)
    reports.clear()
    world.run(0.02)
    assert seen == [], "nothing moving is left to publish"
    assert [r.contacts for r in reports] in ([], [()]), "the contacts ended"
    with pytest.raises(armfleet.UnknownObject, match="no object named 'box'"):
        _ = box.pose
    assert body_id >= 0


def test_set_pose_teleports_an_object_at_rest(world: armfleet.World) -> None:
    table = add_table(world)
    box = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(0.6, 0.0, 0.425))
    world.run(0.1)
    box.set_pose((0.6, 0.2, 0.5), rpy_deg=(0, 0, 90))
    assert np.abs(box.position - (0.6, 0.2, 0.5)).max() < 1e-12
    assert np.abs(box.velocity).max() == 0.0
    assert abs(box.pose[1, 0] - 1.0) < 1e-12, "turned 90 deg about z"
    table.set_pose((1.0, 0.0, 0.2))
    (latched,) = [t for m in world.bus.latched("/tf_static") for t in m.transforms]
    assert np.abs(latched.matrix[:3, 3] - (1.0, 0.0, 0.2)).max() < 1e-12, "re-latched"


def tool0_position(world: armfleet.World, arm: str) -> np.ndarray:
    return world.tf.lookup("world", f"{arm}_tool0")[:3, 3]


def test_an_arm_touching_a_dynamic_object_is_not_stopped(world: armfleet.World) -> None:
    bob = world.spawn("bob", at=(0, 0))
    flange = tool0_position(world, "bob")
    # A box falls on bob's wrist (link6 reaches 22 cm over the flange), from 3 cm above it.
    box = world.add_object(
        "box", "box", size=(0.04, 0.04, 0.04), mass=0.3, at=flange + np.array([0, 0, 0.25])
    )
    reports: list[CollisionReport] = []
    world.bus.subscribe("/collisions", reports.append)
    world.run(0.5)
    touched = {(c.body_a, c.body_b) for r in reports for c in r.contacts}
    assert ("box", "bob") in touched or ("bob", "box") in touched, touched
    assert world.safety.stops == 0
    assert bob.status(world.time).mode is not ArmMode.PROTECTIVE_STOP
    assert box.position[2] < flange[2] + 0.25, "the box fell"


def test_an_arm_touching_a_static_object_stops(world: armfleet.World) -> None:
    bob = world.spawn("bob", at=(0, 0))
    flange = tool0_position(world, "bob")
    # A static post where bob's wrist will be once joint1 has turned 0.5 rad: an obstacle.
    # (A post added in the wrist itself is refused: see test_start_clearance.py.)
    turned = np.array([math.cos(0.5) * flange[0], math.sin(0.5) * flange[0], flange[2] + 0.04])
    world.add_object("post", "box", size=(0.04, 0.04, 0.05), mass=0, at=tuple(turned))
    target = bob.positions
    target[0] += 0.5
    bob.move_to(target)
    world.run(1.5)
    assert world.safety.stops == 1
    status = bob.status(world.time)
    assert status.mode is ArmMode.PROTECTIVE_STOP
    assert "touched post" in status.reason


def test_objects_touching_each_other_or_the_floor_stop_nothing(world: armfleet.World) -> None:
    world.spawn("bob", at=(0, 0))
    add_table(world)
    world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(0.6, -0.2, 0.6))
    world.add_object("ball", "sphere", size=0.03, at=(-0.5, 0.0, 0.2))
    world.run(0.6)
    assert world.contacts.total_contacts > 0
    assert world.safety.stops == 0


def test_an_arm_on_a_table_does_not_touch_it(world: armfleet.World) -> None:
    add_table(world, at=(0.0, 0.0))
    bob = world.spawn("bob", at=(0.0, 0.0, TABLE_TOP_M))
    world.run(0.3)
    assert "table" not in world.contacts.touching_bodies("bob")
    assert world.safety.stops == 0 and bob.position_controller.is_holding


# -- meshes -----------------------------------------------------------------------------
CUBE_CORNERS = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
CUBE_FACES = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]


def write_cube_obj(path: Path, half_m: float) -> Path:
    lines = [f"v {x * half_m} {y * half_m} {z * half_m}" for x, y, z in CUBE_CORNERS]
    lines += [f"f {a} {b} {c} {d}" for a, b, c, d in CUBE_FACES]
    path.write_text("\n".join(lines) + "\n")
    return path


def write_cube_stl(path: Path, half_mm: float) -> Path:
    """A binary STL cube in millimetres."""
    corners = [np.array(c, dtype=float) * half_mm for c in CUBE_CORNERS]
    triangles = []
    for a, b, c, d in CUBE_FACES:
        triangles += [(a, b, c), (a, c, d)]
    data = bytearray(b"armfleet test cube".ljust(80) + struct.pack("<I", len(triangles)))
    for triangle in triangles:
        data += struct.pack("<3f", 0, 0, 0)
        for index in triangle:
            data += struct.pack("<3f", *corners[index - 1])
        data += struct.pack("<H", 0)
    path.write_bytes(bytes(data))
    return path


def test_mesh_objects_from_obj_and_stl_files(world: armfleet.World, tmp_path: Path) -> None:
    obj_file = write_cube_obj(tmp_path / "cube.obj", 0.03)
    stl_file = write_cube_stl(tmp_path / "cube.stl", 25.0)
    cube = world.add_object("cube", "mesh", mesh=obj_file, mass=0.1, at=(0, 0, 0.2))
    brick = world.add_object("brick", "mesh", mesh=stl_file, scale=0.001, at=(0.3, 0, 0.2))
    assert cube.size == pytest.approx((0.06, 0.06, 0.06))
    assert brick.size == pytest.approx((0.05, 0.05, 0.05))
    assert cube.mesh == obj_file.resolve()
    run_until_still(world, cube)
    run_until_still(world, brick)
    # A convex hull carries PyBullet's collision margin: allow a couple of mm.
    assert abs(cube.position[2] - 0.03) < 3e-3
    assert abs(brick.position[2] - 0.025) < 3e-3


# -- names and bad input ----------------------------------------------------------------
BAD_OBJECTS: dict[str, tuple[dict[str, Any], str]] = {
    "unknown shape": (
        {"name": "b", "shape": "cube", "size": (1, 1, 1)},
        "shape: unknown shape 'cube'; valid: box, cylinder, sphere, mesh",
    ),
    "box size length": (
        {"name": "b", "shape": "box", "size": (1, 1)},
        "size: got 2 numbers; a box takes (x, y, z) full extents [m]",
    ),
    "cylinder size length": (
        {"name": "b", "shape": "cylinder", "size": (1, 1, 1)},
        "a cylinder takes (radius, length)",
    ),
    "missing size": ({"name": "b", "shape": "sphere"}, "size: required; a sphere takes (radius,)"),
    "zero size": ({"name": "b", "shape": "sphere", "size": 0.0}, "each must be in (0, 100] m"),
    "nan size": ({"name": "b", "shape": "box", "size": (1, math.nan, 1)}, "each must be in"),
    "negative mass": (
        {"name": "b", "shape": "sphere", "size": 0.1, "mass": -1},
        "mass: -1.0 is outside [0, 10000] kg (0: static)",
    ),
    "colour out of range": (
        {"name": "b", "shape": "sphere", "size": 0.1, "color": (1, 0, 0, 2)},
        "has a value outside [0, 1]",
    ),
    "colour length": (
        {"name": "b", "shape": "sphere", "size": 0.1, "color": (1, 0, 0)},
        "color: expected 4 finite numbers RGBA",
    ),
    "position length": (
        {"name": "b", "shape": "sphere", "size": 0.1, "at": (1, 0)},
        "at: expected 3 finite numbers (x, y, z) [m]",
    ),
    "missing mesh file": (
        {"name": "b", "shape": "mesh", "mesh": "/nonexistent/cup.obj"},
        "mesh: mesh file '/nonexistent/cup.obj' not found",
    ),
    "mesh format": (
        {"name": "b", "shape": "mesh", "mesh": "cup.dae"},
        "unsupported mesh file; use one of .obj, .stl",
    ),
    "mesh without file": ({"name": "b", "shape": "mesh"}, "a mesh object needs mesh="),
    "malformed name": ({"name": "Box", "shape": "sphere", "size": 0.1}, "must match"),
    "reserved name": ({"name": "ground", "shape": "sphere", "size": 0.1}, "reserved"),
    "world name": ({"name": "world", "shape": "sphere", "size": 0.1}, "reserved"),
}


@pytest.mark.parametrize("case", BAD_OBJECTS, ids=list(BAD_OBJECTS))
def test_bad_object_is_refused_and_the_world_unchanged(world: armfleet.World, case: str) -> None:
    given, expected = BAD_OBJECTS[case]
    arguments = dict(given)
    name, shape = arguments.pop("name"), arguments.pop("shape")
    with pytest.raises(armfleet.ObjectError) as raised:
        world.add_object(name, shape, **arguments)
    message = str(raised.value)
    assert "\n" not in message and expected in message, message
    assert world.objects == {}
    assert p.getNumBodies(physicsClientId=world.physics_client) == 1


def test_names_are_unique_across_arms_and_objects(world: armfleet.World) -> None:
    world.spawn("bob", at=(0, 0))
    world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(0.6, 0, 0.025))
    with pytest.raises(armfleet.NameInUse, match="'bob' is already used in this world by an arm"):
        world.add_object("bob", "sphere", size=0.1)
    with pytest.raises(armfleet.NameInUse, match="by an object; names are unique"):
        world.add_object("box", "sphere", size=0.1)
    with pytest.raises(armfleet.NameInUse, match=r"'box' .* by an object"):
        world.spawn("box", at=(2, 0))
    with pytest.raises(armfleet.FrameInUse, match="frame 'bob_tool0', which is arm bob's"):
        world.add_object("bob_tool0", "sphere", size=0.1)
    assert list(world.objects) == ["box"] and list(world.arms) == ["bob"]
    with pytest.raises(armfleet.UnknownObject, match="no object named 'bx'; objects: box"):
        world.remove_object("bx")


def test_a_recording_carries_the_objects_frames(world: armfleet.World, tmp_path: Path) -> None:
    add_table(world)
    box = world.add_object("box", "box", size=(0.05, 0.05, 0.05), at=(0.6, 0.0, 0.6))
    with world.record(tmp_path / "run.mcap", topics=["/tf", "/tf_static"]):
        world.run(0.5)
    recording = armfleet.open_recording(tmp_path / "run.mcap")
    frames = {
        (t["header"]["frame_id"], t["child_frame_id"]): (m.topic, t["transform"]["translation"])
        for m in recording.messages(["/tf", "/tf_static"])
        for t in m.data["transforms"]
    }
    assert frames[("world", "table")][0] == "/tf_static"
    topic, last = frames[("world", "box")]
    assert topic == "/tf"
    assert abs(last["z"] - box.position[2]) < 1e-9
    assert abs(last["z"] - (TABLE_TOP_M + 0.025)) < REST_TOLERANCE_M


def test_a_body_added_after_an_arm_was_removed_rests_on_the_floor() -> None:
    """PyBullet gives a removed body's id to the next body, and its pair filters are kept
    by id: a box taking a removed arm's id fell through the floor, inheriting "no contact
    with the floor" from the arm's base links."""
    with armfleet.World() as world:
        world.spawn("bob", at=(0.0, 0.0))
        world.spawn("gone", at=(0.0, -1.5))
        world.remove("gone")
        world.add_object("crate", "box", size=(0.1, 0.2, 0.05), mass=0.4, at=(0.5, 0.6, 0.2))
        world.run(1.0)
        assert world.objects["crate"].position[2] == pytest.approx(0.025, abs=2e-3)
