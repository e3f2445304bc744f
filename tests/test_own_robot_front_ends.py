"""A robot of one's own in the front ends: the viewer draws its meshes in a real browser,
and a recording holds its prefixed joints, its spawn transform and its description.

The files are vendors' (example-robot-data's UR5, with COLLADA meshes, and SO-100, with
STL meshes), loaded by path with no wrapper. What is expected is read off the files
themselves with ``xml.etree`` and computed with Pinocchio, not asked of armfleet.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader

import armfleet
from tests.test_own_robot import UPSTREAM
from tests.test_viewer_browser import (
    LOAD_TIMEOUT_MS,
    MESH_COUNTS_JS,
    NODE_POSES_JS,
    SCENE_LOADED_JS,
    as_matrix,
    assert_not_blank,
    browser,  # noqa: F401  (the module's browser fixture)
    screenshot,
)
from tests.viewer_helpers import expected_visual_poses

#: Poses in the page follow the simulation to this (the viewer's redraw threshold).
POSE_TOLERANCE = 1e-4
ARMS = {"bob": "ur5", "toby": "so100"}
#: Whether the node at a path has reached an x position (its pose's element 12).
ARRIVED_JS = f"""
([path, x]) => {{
  const pose = ({NODE_POSES_JS})([path])[0];
  return pose !== null && Math.abs(pose[12] - x) < {POSE_TOLERANCE};
}}
"""


def visual_meshes(urdf: Path) -> int:
    """How many ``<visual>`` elements of the file draw a mesh."""
    robot = ET.parse(urdf).getroot()
    return sum(visual.find("geometry/mesh") is not None for visual in robot.iter("visual"))


def movable_joints(urdf: Path) -> list[str]:
    robot = ET.parse(urdf).getroot()
    return [
        joint.get("name", "")
        for joint in robot.iter("joint")
        if joint.get("type") in ("revolute", "prismatic", "continuous")
    ]


@pytest.fixture(scope="module")
def own_arms() -> Iterator[armfleet.World]:
    """A viewed world with a UR5 (bob) and an SO-100 (toby), both by path."""
    world = armfleet.World(viewer=True)
    try:
        assert world.viewer is not None, world.viewer_error
        world.spawn("bob", model=str(UPSTREAM["ur5"]), at=(0.0, 0.0))
        world.spawn("toby", model=str(UPSTREAM["so100"]), at=(1.0, 0.0))
        yield world
    finally:
        world.close()


def test_the_browser_draws_every_mesh_of_both_files_where_pinocchio_puts_it(
    browser: Any,  # noqa: F811
    own_arms: armfleet.World,
) -> None:
    assert own_arms.viewer is not None
    expected = {name: visual_meshes(UPSTREAM[model]) for name, model in ARMS.items()}
    assert all(count > 3 for count in expected.values()), expected
    page = browser.new_page(viewport={"width": 960, "height": 600})
    try:
        page.goto(own_arms.viewer.url)
        page.wait_for_function(SCENE_LOADED_JS, arg=expected, timeout=LOAD_TIMEOUT_MS)
        # A COLLADA file may hold several meshes, an STL one: at least one per visual.
        counts = page.evaluate(MESH_COUNTS_JS, list(ARMS))
        assert all(counts[name] >= expected[name] for name in ARMS), (counts, expected)
        assert_not_blank(screenshot(page, "viewer_own_robots.png"))
        bob = own_arms.arm("bob")
        bob.move_to(np.asarray(bob.positions) + 0.3)
        own_arms.run(2.0)
        poses = expected_visual_poses(bob)
        first = sorted(poses)[0]
        page.wait_for_function(
            ARRIVED_JS, arg=[first, float(poses[first][0, 3])], timeout=LOAD_TIMEOUT_MS
        )
        seen = page.evaluate(NODE_POSES_JS, sorted(poses))
        for path, column_major in zip(sorted(poses), seen, strict=True):
            assert column_major is not None, f"{path} is not in the page"
            error = np.abs(as_matrix(column_major) - poses[path]).max()
            assert error < POSE_TOLERANCE, (path, error)
    finally:
        page.close()


def test_a_recording_holds_the_prefixed_joints_spawn_transform_and_description(
    tmp_path: Path,
) -> None:
    path = tmp_path / "own.mcap"
    with armfleet.World() as world, world.record(path):
        world.spawn("bob", model=str(UPSTREAM["ur5"]), at=(0.5, -0.25, 0.0, 90.0))
        world.run(0.1)
    by_topic: dict[str, list[bytes]] = {}
    with path.open("rb") as stream:  # the official reader, not armfleet's
        for _, channel, message in make_reader(stream).iter_messages():
            by_topic.setdefault(channel.topic, []).append(message.data)
    states = [json.loads(data) for data in by_topic["/bob/joint_states"]]
    assert states and all(
        state["name"] == [f"bob_{joint}" for joint in movable_joints(UPSTREAM["ur5"])]
        for state in states
    )
    transforms = [
        transform
        for data in by_topic["/tf_static"]
        for transform in json.loads(data)["transforms"]
        if transform["child_frame_id"] == "bob_base_link"
    ]
    assert transforms and transforms[-1]["header"]["frame_id"] == "world"
    moved = transforms[-1]["transform"]
    expected = armfleet.SpawnPose(0.5, -0.25, 0.0, 90.0).matrix()
    translation = [moved["translation"][axis] for axis in "xyz"]
    assert np.abs(np.array(translation) - expected[:3, 3]).max() < 1e-9
    quaternion = moved["rotation"]
    assert abs(abs(quaternion["z"]) - np.sin(np.pi / 4)) < 1e-9  # 90 deg about z
    urdf = json.loads(by_topic["/bob/robot_description"][0])["data"]
    links = {link.get("name") for link in ET.fromstring(urdf).iter("link")} - {"world"}
    vendor = {link.get("name") for link in ET.parse(UPSTREAM["ur5"]).getroot().iter("link")}
    assert {f"bob_{link}" for link in vendor - {"world"}} <= links
    meshes = [part.split('"')[0] for part in urdf.split('filename="')[1:]]
    assert meshes and all(Path(m.removeprefix("file://")).is_file() for m in meshes)
