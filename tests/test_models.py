"""Every model in description/ spawns, has its landmarks, tracks a move and can be drawn.

Parametrized over ``ModelLibrary().names``: a model dropped into description/ is
covered without touching this file (issue 8).

Tolerances:
- PyBullet and Pinocchio agree on every link's world pose to 1e-6 (invariant 1);
- a 0.5 rad move of every arm joint tracks to max |q_ref - q| < 1e-3 rad, and the
  arm is within 1e-4 rad of the target 0.2 s after the reference ends (as in
  test_tracking.py); joints off the base_link -> tool0 chain (fingers, a jaw)
  stay within the hold tolerance, 1e-3 rad or m, of where they spawned;
- no contact at all (self, floor), from spawn through both moves: a protective
  stop fires on any contact, so a home pose must stand clear.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from armfleet.description import ModelLibrary
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.messages import (
    ArmMode,
    BringupEvent,
    BringupStage,
    CollisionReport,
    ControllerState,
    FloatArray,
)
from tests.viewer_helpers import SceneState, SceneWatcher, expected_visual_poses, mesh_loader

MODEL_NAMES = ModelLibrary().names
POSE_TOLERANCE = 1e-6
#: The TF tree carries the spawn pose itself: nothing but float rounding between them.
BASE_TOLERANCE = 1e-12
MOVE_RAD = 0.5
MAX_TRACKING_ERROR_RAD = 1e-3
FINAL_ERROR_RAD = 1e-4
SETTLE_S = 0.2
HOLD_TOLERANCE = 1e-3
#: Poses the viewer sends are float32 on the wire (see test_viewer.py).
VIEWER_POSE_TOLERANCE = 1e-4
#: A raised, turned and tilted base: every component of the spawn pose is non-zero.
TILTED = SpawnPose(0.3, -0.2, 0.4, yaw_deg=30.0, roll_deg=10.0, pitch_deg=-15.0)
#: Mesh formats the viewer's loading path (Pinocchio's MeshCat visualizer) sends as files.
VIEWER_MESH_FORMATS = {".stl", ".dae", ".obj"}


def run_until_still(world: armfleet.World, arm: armfleet.Arm, limit_s: float = 10.0) -> None:
    deadline = world.time + limit_s
    while arm.is_moving:
        assert world.time < deadline, f"{arm.name} still moving after {limit_s} s"
        world.run(0.01)


@dataclass
class Moved:
    """bob of one model: brought up, held for 0.5 s, moved out and back home."""

    model: str
    world: armfleet.World
    arm: armfleet.Arm
    bringup: list[BringupEvent]
    collisions: list[CollisionReport]
    home: FloatArray
    #: Positions of the joints off the base_link -> tool0 chain, at the end of bring-up.
    auxiliary_start: FloatArray
    #: Per move: its target, the controller states while the reference moved, the
    #: arm positions SETTLE_S after it stopped.
    targets: list[FloatArray] = field(default_factory=list)
    states: list[list[ControllerState]] = field(default_factory=list)
    settled: list[FloatArray] = field(default_factory=list)


@pytest.fixture(scope="module", params=MODEL_NAMES)
def moved(request: pytest.FixtureRequest) -> Iterator[Moved]:
    model = request.param
    world = armfleet.World()
    try:
        bringup: list[BringupEvent] = []
        collisions: list[CollisionReport] = []
        world.bus.subscribe("/bringup", bringup.append)
        world.bus.subscribe("/collisions", collisions.append)
        arm = world.spawn("bob", model=model, at=(0, 0))
        kinematics = arm.kinematics
        result = Moved(
            model,
            world,
            arm,
            bringup,
            collisions,
            arm.positions,
            arm.body.position[kinematics.auxiliary_indices].copy(),
        )
        world.run(0.5)
        states: list[ControllerState] = []
        world.bus.subscribe("/bob/position_controller/state", states.append)
        lower, upper = arm.joint_limits
        # Every joint towards the roomier side of its range, then back home.
        roomier = np.where(upper - result.home > result.home - lower, 1.0, -1.0)
        for target in (result.home + MOVE_RAD * roomier, result.home):
            states.clear()
            arm.move_to(target)
            run_until_still(world, arm)
            result.targets.append(target)
            result.states.append(list(states))
            world.run(SETTLE_S)
            result.settled.append(arm.positions)
        yield result
    finally:
        world.close()


def test_bring_up_reaches_ready_at_home(moved: Moved) -> None:
    stages = [event.stage for event in moved.bringup if event.arm == "bob"]
    assert stages == list(BringupStage)
    ready = moved.bringup[-1]
    print(f"{moved.model}: ready after {ready.wall_time:.3f} s (wall), {ready.stamp:.3f} s (sim)")
    description = moved.arm.description
    assert np.abs(moved.home - np.array(description.home)).max() < HOLD_TOLERANCE


def test_no_contact_from_spawn_to_the_end(moved: Moved) -> None:
    touching = {(c.link_a, c.link_b) for report in moved.collisions for c in report.contacts}
    assert touching == set(), f"{moved.model} touches at or near home: {touching}"
    assert moved.arm.mode is ArmMode.HOLDING


def test_landmark_frames_are_on_tf(moved: Moved) -> None:
    tf, arm = moved.world.tf, moved.arm
    base = tf.lookup("world", "bob_base_link")
    assert np.abs(base - SpawnPose(0, 0).matrix()).max() < BASE_TOLERANCE
    arm.kinematics.update(arm.joint_state.position)
    tool0 = tf.lookup("world", "bob_tool0")
    assert np.abs(tool0 - arm.kinematics.world_pose("bob_tool0")).max() < POSE_TOLERANCE


def test_move_of_every_joint_tracks_and_settles(moved: Moved) -> None:
    assert np.all(np.abs(moved.targets[0] - moved.home) >= 0.4)
    worst = 0.0
    for target, states, settled in zip(moved.targets, moved.states, moved.settled, strict=True):
        assert len(states) > 100, "the move took at least 0.1 s"
        errors = np.array([s.reference_position - s.position for s in states])
        worst = max(worst, float(np.abs(errors).max()))
        assert np.abs(states[-1].reference_position - target).max() < 1e-9
        final = np.abs(settled - target).max()
        assert final < FINAL_ERROR_RAD, f"{moved.model}: {final:.2e} rad from the target"
    print(f"{moved.model}: max tracking error {worst:.3e} rad")
    assert worst < MAX_TRACKING_ERROR_RAD


def test_joints_off_the_chain_hold_still(moved: Moved) -> None:
    auxiliary = moved.arm.body.position[moved.arm.kinematics.auxiliary_indices]
    assert np.all(np.abs(auxiliary - moved.auxiliary_start) < HOLD_TOLERANCE)


# -- kinematics: PyBullet and Pinocchio -----------------------------------------------------


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_pybullet_and_pinocchio_agree_at_random_configurations(model: str) -> None:
    with armfleet.World() as world:
        arm = world.spawn("bob", model=model, at=TILTED)
        kinematics = arm.kinematics
        links = arm.body.link_names
        # The body is lean on purpose (docs/performance.md): PyBullet simulates exactly
        # the links with mass or a collision shape; the landmarks (base_link, tool0,
        # world) are frames of the Pinocchio model only, compared with TF below.
        assert set(links) == links_with_mass_or_shape(arm.description.urdf)
        landmarks = set(kinematics.link_names) - set(links) - {"world"}
        assert "bob_tool0" in landmarks
        rng = np.random.default_rng(8)
        for _ in range(3):
            q = kinematics.lower + (kinematics.upper - kinematics.lower) * rng.uniform(
                0.05, 0.95, kinematics.lower.size
            )
            # Teleported; the world is not stepped again, so no controller acts on it.
            arm.body.reset(q)
            kinematics.update(arm.body.position)
            for link in links:
                from_bullet = arm.body.link_world_pose(link)
                from_pinocchio = kinematics.world_pose(link)
                assert np.abs(from_bullet - from_pinocchio).max() < POSE_TOLERANCE, link
        world.step()  # the landmarks on TF, where the arm now is
        kinematics.update(arm.joint_state.position)
        for landmark in landmarks:
            from_tf = world.tf.lookup("world", landmark)
            assert np.abs(from_tf - kinematics.world_pose(landmark)).max() < POSE_TOLERANCE


def links_with_mass_or_shape(urdf: str) -> set[str]:
    """Links of a URDF with a collision shape or a positive mass."""
    found = set()
    for link in ET.fromstring(urdf).iter("link"):
        mass = link.find("inertial/mass")
        if link.find("collision") is not None or (
            mass is not None and float(mass.get("value", "0")) > 0
        ):
            found.add(link.get("name", ""))
    return found


# -- visuals: meshes resolve, and the viewer draws every one ------------------------------


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_visual_meshes_resolve_and_load(model: str) -> None:
    """Pinocchio's visual model (what the viewer draws) has one loaded mesh per <visual>."""
    description = ModelLibrary().expand(model, "bob_")
    robot = ET.fromstring(description.urdf)
    visuals = [visual for link in robot.iter("link") for visual in link.findall("visual")]
    assert visuals, f"{model} has nothing to draw"
    model_ = pin.buildModelFromXML(description.urdf)
    geometry = pin.buildGeomFromUrdfString(
        model_, description.urdf, pin.GeometryType.VISUAL, mesh_loader=mesh_loader()
    )
    assert len(geometry.geometryObjects) == len(visuals)
    for item in geometry.geometryObjects:
        path = Path(item.meshPath)
        assert path.is_absolute() and path.is_file(), (item.name, item.meshPath)
        assert path.suffix.lower() in VIEWER_MESH_FORMATS, (item.name, path.suffix)
        assert item.geometry.num_vertices > 0, item.name


@pytest.fixture(scope="module")
def viewed() -> Iterator[tuple[armfleet.World, SceneState]]:
    """One arm of every model, each named after its model, in a world with a viewer."""
    world = armfleet.World(viewer=True)
    try:
        assert world.viewer is not None, world.viewer_error
        for index, model in enumerate(MODEL_NAMES):
            world.spawn(model, model=model, at=(1.5 * index, 0))
        with SceneWatcher(world.viewer.port) as watcher:
            scene = watcher.wait_quiet()
        yield world, scene
    finally:
        world.close()


def mesh_bytes(scene: SceneState, path: str) -> int:
    """Size of the mesh file a ``set_object`` sent for ``path``, following the viewer's
    reference to an identical mesh sent before (MeshCat's two layouts: a mesh-file
    object for DAE/OBJ, a Mesh with a mesh-file geometry for STL)."""
    command: dict[str, Any] = scene.objects[path]["object"]
    inner = command["object"]
    if inner["type"] == "_meshfile_object":
        if inner["data"]:
            return len(inner["data"])
        shared = inner.get("armfleet_mesh")
        sent = [
            len(other["object"]["object"]["data"])
            for other in scene.objects.values()
            if other["object"]["object"].get("armfleet_mesh") == shared
        ]
        return max(sent) if shared is not None else 0
    (geometry,) = command["geometries"]
    assert geometry["type"] == "_meshfile", geometry["type"]
    return len(geometry["data"].data)


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_viewer_draws_every_visual(viewed: tuple[armfleet.World, SceneState], model: str) -> None:
    world, scene = viewed
    expected = expected_visual_poses(world.arm(model))
    nodes = scene.nodes_under(f"/meshcat/armfleet/{model}/visuals")
    assert nodes == sorted(expected)
    for node in nodes:
        assert mesh_bytes(scene, node) > 1000, node
        assert np.abs(scene.transforms[node] - expected[node]).max() < VIEWER_POSE_TOLERANCE


# -- the docs' table of models (docs/descriptions-and-specs.md) ----------------------------


def test_docs_table_lists_every_model_and_its_home() -> None:
    page = Path(__file__).resolve().parents[1] / "docs" / "descriptions-and-specs.md"
    rows = re.findall(r"^\| (\w+) \| `[^`]+` \| [^|]+ \| ([^|]+) \|", page.read_text(), re.M)
    assert sorted(model for model, _ in rows) == MODEL_NAMES
    library = ModelLibrary()
    for model, home in rows:
        if home.strip().startswith("`"):
            written = tuple(float(v) for v in home.strip().strip("`").split())
            assert written == library.expand(model, "bob_").home, model
