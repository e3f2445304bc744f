"""A page opened before the arms come: every frame it draws frames every arm, and it says
the meshes are loading until they are all in it (issue 28, item 22).

In Debian's headless Chromium, driven by Playwright. The page is opened while
``armfleet.launch`` has made the world but brought no arm up yet; a script run before
the page's own records, for every frame WebGL draws, where the arms' spawn positions
fall on the screen (three.js projection with the page's camera) and whether the
loading line is up.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest

import armfleet
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.spec import ArmSpec, FleetSpec
from tests.viewer_helpers import headless_browser

VIEWPORT = {"width": 960, "height": 600}
#: Caps on page events; software WebGL on 2 shared cores takes seconds per Panda.
LOAD_TIMEOUT_MS = 90_000
PANDA_MESHES = 11
#: Far apart and off the axes: the first arm framed alone leaves the second off screen;
#: no link of either stands at the origin, where a mesh not placed yet stands.
SPEC = FleetSpec(
    arms=(
        ArmSpec("bob", "panda", SpawnPose(0.3, -0.2)),
        ArmSpec("toby", "panda", SpawnPose(2.4, 1.2, 0.0, 180.0)),
    ),
    source="the first-frame test",
)
BASES = [[arm.pose.x, arm.pose.y, arm.pose.z] for arm in SPEC.arms]

# Runs before the page's scripts: wraps the renderer of the page's `viewer` as it is
# made, and notes for every frame drawn the arms' meshes in the scene, the screen
# position (normalized device coordinates) of each spawn position under /meshcat, and
# the loading line.
RECORD_FRAMES_JS = """
window.armfleetFrames = [];
window.armfleetBases = BASES;
window.armfleetDescribe = function (v) {
  const THREE = MeshCat.THREE;
  const root = v.scene_tree.children["meshcat"];
  const fleet = root && root.children["armfleet"];
  let meshes = 0;  // of the arms' visuals (not their target markers)
  let unplaced = 0;  // visual nodes still at the origin, where a new object stands
  for (const arm of Object.values(fleet ? fleet.children : {})) {
    const visuals = arm.children["visuals"];
    if (visuals) visuals.object.traverse((o) => { if (o.isMesh) meshes += 1; });
    for (const node of Object.values(visuals ? visuals.children : {})) {
      if (node.object.position.lengthSq() === 0) unplaced += 1;
    }
  }
  v.scene.updateMatrixWorld(true);
  v.camera.updateMatrixWorld(true);
  const world = root ? root.object.matrixWorld : new THREE.Matrix4();
  const screen = window.armfleetBases.map(
    (p) => new THREE.Vector3(p[0], p[1], p[2]).applyMatrix4(world).project(v.camera).toArray());
  const line = document.getElementById("armfleet-loading");
  return {meshes: meshes, unplaced: unplaced, screen: screen, framed: root !== undefined,
          loading: line !== null && !line.hidden, text: line ? line.textContent : null};
};
let made;
Object.defineProperty(window, "viewer", {
  configurable: true,
  get() { return made; },
  set(v) {
    made = v;
    const draw = v.renderer.render.bind(v.renderer);
    v.renderer.render = function (scene, camera) {
      draw(scene, camera);
      window.armfleetFrames.push(window.armfleetDescribe(v));
    };
  },
});
""".replace("BASES", json.dumps(BASES))
LOADING_LINE_JS = """() => {
  const line = document.getElementById("armfleet-loading");
  return {shown: !line.hidden, text: line.textContent};
}"""
ALL_MESHES_JS = f"() => armfleetDescribe(viewer).meshes >= {2 * PANDA_MESHES}"


def on_screen(point: list[float]) -> bool:
    """Whether a projected point is inside the view: in the viewport, before the far plane."""
    x, y, z = point
    return -1.0 < x < 1.0 and -1.0 < y < 1.0 and -1.0 < z < 1.0


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with headless_browser() as launched:
        yield launched


def test_every_frame_frames_every_arm_and_the_page_says_loading(browser: Any) -> None:
    tab = browser.new_page(viewport=VIEWPORT)
    tab.add_init_script(RECORD_FRAMES_JS)
    before_any_mesh: dict[str, Any] = {}

    def open_page(world: armfleet.World) -> None:
        """The world is made, no arm is up: the page opens now."""
        assert world.viewer is not None, world.viewer_error
        tab.goto(world.viewer.url)
        tab.wait_for_function(
            "() => document.getElementById('armfleet-loading').textContent.includes('toby')",
            timeout=LOAD_TIMEOUT_MS,
        )
        before_any_mesh.update(tab.evaluate("() => armfleetDescribe(viewer)"))
        before_any_mesh["line"] = tab.evaluate(LOADING_LINE_JS)

    try:
        world = armfleet.launch(SPEC, viewer=True, before_spawn=open_page)
        try:
            tab.wait_for_function(ALL_MESHES_JS, timeout=LOAD_TIMEOUT_MS)
            tab.wait_for_function(
                "() => document.getElementById('armfleet-loading').hidden",
                timeout=LOAD_TIMEOUT_MS,
            )
            tab.wait_for_function(  # drawing waits while meshes come: until a frame is drawn
                f"() => armfleetFrames.some((f) => f.meshes >= {2 * PANDA_MESHES})",
                timeout=LOAD_TIMEOUT_MS,
            )
            frames = tab.evaluate("() => armfleetFrames")
            final = tab.evaluate("() => armfleetDescribe(viewer)")
        finally:
            world.close()
    finally:
        tab.close()

    # Before any mesh: the loading line names the arms to come; the camera frames them.
    assert before_any_mesh["meshes"] == 0
    assert before_any_mesh["line"] == {
        "shown": True,
        "text": "0 of 2 arms shown; waiting for bob, toby…",
    }
    assert all(on_screen(p) for p in before_any_mesh["screen"]), before_any_mesh["screen"]
    # Every frame drawn with a mesh in it had both spawn positions in view, every mesh
    # where its arm puts it, and the loading line up until every mesh was in.
    drawn = [frame for frame in frames if frame["meshes"] > 0]
    assert drawn, "the page drew no frame with an arm"
    for frame in drawn:
        assert all(on_screen(p) for p in frame["screen"]), frame
        assert frame["unplaced"] == 0, frame
        if frame["meshes"] < 2 * PANDA_MESHES:
            assert frame["loading"], frame
    # Once the line went, every mesh was in and both arms were still in view.
    assert final["meshes"] == 2 * PANDA_MESHES and not final["loading"]
    assert all(on_screen(p) for p in final["screen"])
