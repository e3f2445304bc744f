"""The viewer in a real browser: Debian's headless Chromium driven by Playwright.

Skipped only when /usr/bin/chromium is missing on a developer machine; under
CI a missing browser fails. Screenshots go to ``test-artifacts/``.
"""

from __future__ import annotations

import io
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

import armfleet
from armfleet.messages import PlannedMotion
from armfleet.viewer.plan_lines import PLAN_COLOR
from armfleet.viewer.scene import BACKGROUND_TOP
from tests.viewer_helpers import bob_and_toby_viewed, expected_visual_poses, headless_browser

VIEWPORT_WIDTH, VIEWPORT_HEIGHT = 960, 600
ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"
#: Every wait below is for a page state (an event); this caps it. Software WebGL on 2 cores
#: shared with another pytest worker takes seconds per Panda: leave a wide margin.
LOAD_TIMEOUT_MS = 90_000
PANDA_MESHES = 11
#: Browser poses are float64 from the server; the viewer redraws an arm once it
#: moved 1e-5 rad, so a page is within 1e-4 m of the simulation.
POSE_TOLERANCE = 1e-4

# Meshes loaded under each arm's visuals node (a node holds its mesh under "<object>").
MESH_COUNTS_JS = """
(names) => {
  const root = viewer.scene_tree.children["meshcat"];
  const fleet = root && root.children["armfleet"];
  const counts = {};
  for (const name of names) {
    const visuals = fleet && fleet.children[name] && fleet.children[name].children["visuals"];
    let meshes = 0;
    if (visuals) visuals.object.traverse((o) => { if (o.isMesh) meshes += 1; });
    counts[name] = meshes;
  }
  return counts;
}
"""
SCENE_LOADED_JS = f"""
(expected) => {{
  if (typeof viewer === "undefined" || !viewer.scene_tree) return false;
  const counts = ({MESH_COUNTS_JS})(Object.keys(expected));
  return Object.keys(expected).every((name) => counts[name] >= expected[name]);
}}
"""
# The local pose (column-major) of nodes given by path; null for a missing one.
NODE_POSES_JS = """
(paths) => paths.map((path) => {
  let node = viewer.scene_tree;
  for (const part of path.split("/").filter((p) => p.length)) {
    node = node.children[part];
    if (node === undefined) return null;
  }
  const o = node.object;
  return new MeshCat.THREE.Matrix4().compose(o.position, o.quaternion, o.scale).toArray();
})
"""
# Screen rectangle [x0, y0, x1, y1] in pixels of each arm's meshes.
ARM_RECTS_JS = """
(names) => {
  const THREE = MeshCat.THREE;
  const fleet = viewer.scene_tree.children["meshcat"].children["armfleet"];
  viewer.scene.updateMatrixWorld(true);
  const width = viewer.renderer.domElement.clientWidth;
  const height = viewer.renderer.domElement.clientHeight;
  const rects = {};
  for (const name of names) {
    const box = new THREE.Box3().setFromObject(fleet.children[name].object);
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (const x of [box.min.x, box.max.x]) for (const y of [box.min.y, box.max.y])
      for (const z of [box.min.z, box.max.z]) {
        const p = new THREE.Vector3(x, y, z).project(viewer.camera);
        const px = (p.x + 1) / 2 * width, py = (1 - p.y) / 2 * height;
        x0 = Math.min(x0, px); x1 = Math.max(x1, px); y0 = Math.min(y0, py); y1 = Math.max(y1, py);
      }
    rects[name] = [x0, y0, x1, y1];
  }
  return rects;
}
"""
SET_ARMS_VISIBLE_JS = """
([names, visible]) => {
  const fleet = viewer.scene_tree.children["meshcat"].children["armfleet"];
  for (const name of names) fleet.children[name].object.visible = visible;
  viewer.set_dirty();
}
"""
# Animation actions of the replay, grouped by the arm they move.
REPLAY_ACTIONS_JS = """
() => {
  const byArm = {};
  for (const action of viewer.animator.actions) {
    let node = action.getRoot();
    while (node.parent && node.parent.name !== "armfleet") node = node.parent;
    const tracks = action.getClip().tracks.map((t) => t.name).sort();
    (byArm[node.name] = byArm[node.name] || []).push(tracks.join(","));
  }
  return {byArm: byArm, duration: viewer.animator.duration};
}
"""
SEEK_JS = f"""
([time, paths]) => {{
  viewer.animator.pause();
  viewer.animator.seek(time);
  return ({NODE_POSES_JS})(paths);
}}
"""


# Per scene object under /meshcat/objects: its meshes and their colours (hex RGB).
OBJECT_MESHES_JS = """
(names) => {
  const root = viewer.scene_tree.children["meshcat"];
  const objects = root && root.children["objects"];
  const found = {};
  for (const name of names) {
    const node = objects && objects.children[name];
    const colors = [];
    if (node) node.object.traverse((o) => {
      if (o.isMesh) colors.push(o.material.color.getHex());
    });
    found[name] = colors;
  }
  return found;
}
"""
OBJECTS_LOADED_JS = f"""
(names) => {{
  if (typeof viewer === "undefined" || !viewer.scene_tree) return false;
  const found = ({OBJECT_MESHES_JS})(names);
  return names.every((name) => found[name].length > 0);
}}
"""


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Debian's Chromium, headless, launched by Playwright (never a downloaded browser)."""
    with headless_browser() as launched:
        yield launched


@pytest.fixture(scope="module")
def live() -> Iterator[armfleet.World]:
    """A world with a viewer, bob at (0, 0) and toby at (1, 0)."""
    with bob_and_toby_viewed() as world:
        yield world


@dataclass
class LivePage:
    tab: Any
    #: Time from opening the page to every mesh of both arms in the scene [s].
    full_scene_s: float


@pytest.fixture(scope="module")
def live_page(browser: Any, live: armfleet.World) -> Iterator[LivePage]:
    """The live page, with both arms' meshes loaded."""
    assert live.viewer is not None
    tab = browser.new_page(viewport={"width": VIEWPORT_WIDTH, "height": VIEWPORT_HEIGHT})
    try:
        started = time.perf_counter()
        tab.goto(live.viewer.url)
        tab.wait_for_function(
            SCENE_LOADED_JS,
            arg={"bob": PANDA_MESHES, "toby": PANDA_MESHES},
            timeout=LOAD_TIMEOUT_MS,
        )
        yield LivePage(tab, time.perf_counter() - started)
    finally:
        tab.close()


def screenshot(tab: Any, name: str | None = None) -> np.ndarray:
    """RGB pixels of the page once it has drawn its latest changes."""
    tab.wait_for_function("() => !viewer.needs_render", timeout=LOAD_TIMEOUT_MS)
    tab.evaluate("() => new Promise((done) => requestAnimationFrame(() => done()))")
    png = tab.screenshot()
    if name is not None:
        ARTIFACTS.mkdir(exist_ok=True)
        (ARTIFACTS / name).write_bytes(png)
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def assert_not_blank(pixels: np.ndarray) -> None:
    white = (pixels > 235).all(axis=2).mean()
    assert white < 0.5, f"{white:.0%} of the page is white"
    assert pixels.std() > 10, "the page is one flat colour"
    corner = pixels[3, 3]
    background = np.array(BACKGROUND_TOP) * 255
    assert np.abs(corner - background).max() < 16, f"background {corner}, expected {background}"


def changed_share(before: np.ndarray, after: np.ndarray, rect: list[float]) -> float:
    """Share of the pixels of ``rect`` (clipped to the image) that differ visibly."""
    height, width = before.shape[:2]
    x0, y0 = max(int(rect[0]), 0), max(int(rect[1]), 0)
    x1, y1 = min(int(rect[2]) + 1, width), min(int(rect[3]) + 1, height)
    assert x1 - x0 > 20 and y1 - y0 > 20, f"arm rectangle {rect} is off screen"
    diff = np.abs(before[y0:y1, x0:x1] - after[y0:y1, x0:x1]).sum(axis=2) > 40
    return float(diff.mean())


def link_path(arm: str, link: str) -> str:
    return f"/meshcat/armfleet/{arm}/visuals/{arm}_panda_{link}_0"


def as_matrix(column_major: list[float]) -> np.ndarray:
    return np.array(column_major, dtype=float).reshape(4, 4).T


def test_page_shows_both_arms(live_page: LivePage) -> None:
    page = live_page.tab
    counts = page.evaluate(MESH_COUNTS_JS, ["bob", "toby"])
    assert counts == {"bob": PANDA_MESHES, "toby": PANDA_MESHES}
    print(f"full scene in the browser after {live_page.full_scene_s:.1f} s")
    shown = screenshot(page, "viewer_live.png")
    assert_not_blank(shown)
    rects = page.evaluate(ARM_RECTS_JS, ["bob", "toby"])
    assert (rects["bob"][0] + rects["bob"][2]) < (rects["toby"][0] + rects["toby"][2]), (
        "bob (x = 0) is left of toby (x = 1) seen from the front"
    )
    page.evaluate(SET_ARMS_VISIBLE_JS, [["bob", "toby"], False])
    try:
        empty = screenshot(page)
    finally:
        page.evaluate(SET_ARMS_VISIBLE_JS, [["bob", "toby"], True])
    for name, rect in rects.items():
        share = changed_share(shown, empty, rect)
        assert share > 0.05, f"{name}: only {share:.1%} of its rectangle shows the arm"


def test_page_follows_toby_and_not_bob(live_page: LivePage, live: armfleet.World) -> None:
    page = live_page.tab
    toby = live.arm("toby")
    paths = [link_path("bob", "link7"), link_path("toby", "link7")]
    bob_before, toby_before = (as_matrix(m) for m in page.evaluate(NODE_POSES_JS, paths))
    lower, upper = toby.joint_limits
    toby.move_to(np.clip(toby.positions + 0.5, lower + 0.1, upper - 0.1))
    while toby.is_moving:
        live.run(0.1)
    live.run(0.1)
    expected = expected_visual_poses(toby)[paths[1]]
    page.wait_for_function(
        f"""([paths, expected, tolerance]) => {{
            const pose = ({NODE_POSES_JS})(paths)[1];
            return pose.every((v, i) => Math.abs(v - expected[i]) < tolerance);
        }}""",
        arg=[paths, expected.T.flatten().tolist(), POSE_TOLERANCE],
        timeout=LOAD_TIMEOUT_MS,
    )
    bob_after, toby_after = (as_matrix(m) for m in page.evaluate(NODE_POSES_JS, paths))
    assert np.abs(toby_after[:3, 3] - toby_before[:3, 3]).max() > 0.05, "toby moved"
    assert np.abs(bob_after - bob_before).max() < 1e-9, "bob did not move in the browser"
    screenshot(page, "viewer_live_after_move.png")


def test_replay_plays_from_file(browser: Any, live: armfleet.World, tmp_path: Path) -> None:
    """The saved replay holds the whole run: toby moves in it (this test moves him, so it
    holds whichever tests of this file ran before it on its pytest worker), bob holds."""
    assert live.viewer is not None
    toby = live.arm("toby")
    lower, upper = toby.joint_limits
    toby.move_to(np.clip(toby.positions - 0.4, lower + 0.1, upper - 0.1))
    while toby.is_moving:
        live.run(0.1)
    live.run(0.1)
    replay = live.viewer.save(tmp_path / "run.html")
    tab = browser.new_page(viewport={"width": VIEWPORT_WIDTH, "height": VIEWPORT_HEIGHT})
    try:
        tab.goto(replay.resolve().as_uri())
        tab.wait_for_function(
            SCENE_LOADED_JS,
            arg={"bob": PANDA_MESHES, "toby": PANDA_MESHES},
            timeout=LOAD_TIMEOUT_MS,
        )
        tab.wait_for_function("() => viewer.animator.actions.length > 0", timeout=LOAD_TIMEOUT_MS)
        actions = tab.evaluate(REPLAY_ACTIONS_JS)
        assert set(actions["byArm"]) == {"bob", "toby"}, "one track set per arm"
        for name, tracks in actions["byArm"].items():
            moving = [t for t in tracks if t == ".position,.quaternion"]
            assert len(moving) == PANDA_MESHES + 1, f"{name}: visuals and tool0"
            assert set(tracks) <= {".position,.quaternion", ".visible"}
        assert abs(actions["duration"] - live.time) < 0.1, "the replay spans the whole run"

        paths = [link_path("bob", "link7"), link_path("toby", "link7")]
        start = [as_matrix(m) for m in tab.evaluate(SEEK_JS, [0.0, paths])]
        end = [as_matrix(m) for m in tab.evaluate(SEEK_JS, [actions["duration"], paths])]
        assert np.abs(end[1][:3, 3] - start[1][:3, 3]).max() > 0.05, "toby moves in the replay"
        assert np.abs(end[0][:3, 3] - start[0][:3, 3]).max() < 1e-3, "bob holds in the replay"
        now = expected_visual_poses(live.arm("toby"))[paths[1]]
        assert np.abs(end[1] - now).max() < 1e-3, "the replay ends where toby is"
        assert_not_blank(screenshot(tab, "viewer_replay.png"))
    finally:
        tab.close()


def test_objects_in_the_live_page_and_the_replay(browser: Any, tmp_path: Path) -> None:
    cube = tmp_path / "cube.obj"
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    cube.write_text(
        "".join(f"v {x * 0.03} {y * 0.03} {z * 0.03}\n" for x, y, z in corners)
        + "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    )
    names = ["table", "can", "ball", "cube"]
    with armfleet.World(viewer=True) as world:
        assert world.viewer is not None, world.viewer_error
        world.add_object(
            "table", "box", size=(0.8, 0.6, 0.3), mass=0, at=(0, 0, 0.15), color=(1, 0, 0, 1)
        )
        can = world.add_object("can", "cylinder", size=(0.04, 0.12), at=(0.2, 0, 0.5))
        world.add_object("ball", "sphere", size=0.05, at=(-0.2, 0, 0.5), color=(0, 1, 0, 1))
        world.add_object("cube", "mesh", mesh=cube, at=(0, 0.15, 0.5), color=(0, 0, 1, 1))
        world.run(1.0)  # everything falls onto the table
        assert can.position[2] == pytest.approx(0.36, abs=1e-3)
        world.viewer.refresh()
        replay = world.viewer.save(tmp_path / "objects.html")
        tab = browser.new_page(viewport={"width": VIEWPORT_WIDTH, "height": VIEWPORT_HEIGHT})
        try:
            tab.goto(world.viewer.url)
            tab.wait_for_function(OBJECTS_LOADED_JS, arg=names, timeout=LOAD_TIMEOUT_MS)
            colors = tab.evaluate(OBJECT_MESHES_JS, names)
            assert colors["table"] == [0xFF0000] and colors["ball"] == [0x00FF00]
            assert colors["cube"] == [0x0000FF]
            (node,) = tab.evaluate(NODE_POSES_JS, ["/meshcat/objects/can"])
            shown = as_matrix(node)
            assert np.abs(shown[:3, 3] - can.position).max() < POSE_TOLERANCE
            # MeshCat's cylinder axis (y) is turned onto the can's axis (z).
            assert np.abs(shown[:3, 1] - can.pose[:3, 2]).max() < 1e-6
            assert_not_blank(screenshot(tab, "viewer_objects.png"))
        finally:
            tab.close()
    tab = browser.new_page(viewport={"width": VIEWPORT_WIDTH, "height": VIEWPORT_HEIGHT})
    try:
        tab.goto(replay.resolve().as_uri())
        tab.wait_for_function(OBJECTS_LOADED_JS, arg=names, timeout=LOAD_TIMEOUT_MS)
        tab.wait_for_function("() => viewer.animator.actions.length > 0", timeout=LOAD_TIMEOUT_MS)
        path = ["/meshcat/objects/can"]
        start = as_matrix(tab.evaluate(SEEK_JS, [0.0, path])[0])
        end = as_matrix(tab.evaluate(SEEK_JS, [1.0, path])[0])
        assert start[2, 3] == pytest.approx(0.5, abs=1e-3), "the can starts in the air"
        assert end[2, 3] == pytest.approx(0.36, abs=1e-3), "and ends on the table"
    finally:
        tab.close()


# The planned-motion line of an arm in the page's scene: its vertex count and colour; null
# when the arm's node has none.
PLAN_LINE_JS = """
(arm) => {
  const root = viewer.scene_tree.children["meshcat"];
  const fleet = root && root.children["armfleet"];
  const node = fleet && fleet.children[arm] && fleet.children[arm].children["planned_motion"];
  if (!node) return null;
  let found = null;
  node.object.traverse((o) => {
    if (o.isLine) found = {vertices: o.geometry.attributes.position.count,
                           color: o.material.color.getHex(), visible: o.visible};
  });
  return found;
}
"""


def plan_colored_pixels(pixels: np.ndarray) -> int:
    """Pixels of the planned-motion magenta: red and blue well above green. The 1 px line
    is anti-aliased into what is behind it; nothing else in the scene (grey arms, blue-grey
    sky, dark grid, orange target, the origin's red, green and blue axes) is magenta."""
    red, green, blue = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    return int(((red - green > 80) & (blue - green > 60)).sum())


def test_page_draws_a_planned_path_while_it_runs(live_page: LivePage, live: armfleet.World) -> None:
    """After the replay test (bob holds until then): bob plans around toby; the page holds
    the line of the announced tool path while bob moves, and not once he stands still."""
    page = live_page.tab
    bob = live.arm("bob")
    announced: list[PlannedMotion] = []
    subscription = live.bus.subscribe("/bob/planned_motion", announced.append)
    try:
        assert page.evaluate(PLAN_LINE_JS, "bob") is None
        goal = np.array(bob.description.home) + np.array([0.9, 0.4, 0.0, 0.3, 0.0, 0.2, 0.0])
        bob.move_to(goal, avoid_collisions=True)
        live.step()
        [plan] = announced
        page.wait_for_function(f"() => ({PLAN_LINE_JS})('bob') !== null", timeout=LOAD_TIMEOUT_MS)
        line = page.evaluate(PLAN_LINE_JS, "bob")
        assert line == {"vertices": len(plan.tool_path), "color": PLAN_COLOR, "visible": True}
        assert plan_colored_pixels(screenshot(page, "viewer_planned_path.png")) >= 20
        while bob.is_moving:
            live.run(0.05)
        live.step()
        page.wait_for_function(f"() => ({PLAN_LINE_JS})('bob') === null", timeout=LOAD_TIMEOUT_MS)
        assert plan_colored_pixels(screenshot(page)) <= 2
    finally:
        subscription.cancel()
