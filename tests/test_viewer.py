"""The MeshCat viewer without a browser: scene, live updates, replay, server process, failures.

A websocket client (:class:`SceneWatcher`) stands in for the browser: it gets
the very messages a page gets. The page itself is tested in
``test_viewer_browser.py``.
"""

from __future__ import annotations

import base64
import json
import os
import re
import signal
import socket
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
import umsgpack
import zmq

import armfleet
from armfleet.viewer import DISPLAY_RATE_HZ, Viewer, ViewerError
from armfleet.viewer.connection import BridgeConnection
from armfleet.viewer.replay import quaternions_xyzw
from tests.viewer_helpers import (
    SceneWatcher,
    bob_and_toby_viewed,
    expected_visual_poses,
    non_loopback_ipv4,
    process_alive,
    stalled_browser,
    tool0_pose,
    wait_until_gone,
)

#: An arm is redrawn once it moved 1e-5 rad (armfleet.viewer.arm_visual.REDRAW_TOLERANCE):
#: with ~1 m of arm, what a page shows is within 1e-4 m of the simulation.
POSE_TOLERANCE = 1e-4


@pytest.fixture(scope="module")
def viewed() -> Iterator[armfleet.World]:
    """A world with a viewer, bob at (0, 0) and toby at (1, 0)."""
    with bob_and_toby_viewed() as world:
        yield world


def viewer_of(world: armfleet.World) -> Viewer:
    assert isinstance(world.viewer, Viewer), world.viewer_error
    return world.viewer


def nudge(arm: armfleet.Arm, delta: float) -> np.ndarray:
    """A target ``delta`` rad from where the arm is, kept 0.1 rad inside the limits."""
    lower, upper = arm.joint_limits
    target: np.ndarray = np.clip(arm.positions + delta, lower + 0.1, upper - 0.1)
    return target


def settle(world: armfleet.World, arm: armfleet.Arm, limit_s: float = 10.0) -> None:
    while arm.is_moving and limit_s > 0:
        world.run(0.1)
        limit_s -= 0.1
    world.run(0.1)


def max_pose_error(seen: dict[str, np.ndarray], expected: dict[str, np.ndarray]) -> float:
    """Largest difference of a pose entry; infinite if a node was not seen yet."""
    return max(
        float(np.abs(seen[path] - pose).max()) if path in seen else np.inf
        for path, pose in expected.items()
    )


# -- import ----------------------------------------------------------------------------
def test_importing_armfleet_loads_no_viewer_dependency() -> None:
    code = (
        "import sys, armfleet, armfleet.viewer; "
        "print([m for m in ('meshcat', 'tornado', 'umsgpack', 'pinocchio.visualize') "
        "if m in sys.modules])"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


def test_public_names_resolve() -> None:
    import armfleet.viewer

    for name in armfleet.viewer.__all__:
        assert getattr(armfleet.viewer, name) is not None, name


# -- scene -----------------------------------------------------------------------------
def test_each_arm_loads_once_under_its_own_node(viewed: armfleet.World) -> None:
    with SceneWatcher(viewer_of(viewed).port) as watcher:
        scene = watcher.wait_quiet()
    for name in ("bob", "toby"):
        arm = viewed.arm(name)
        expected = expected_visual_poses(arm)
        visuals = scene.nodes_under(f"/meshcat/armfleet/{name}/visuals")
        assert visuals == sorted(expected), f"{name}: one node per visual geometry"
        assert len(visuals) == 11  # Panda: link0-7, hand, two fingers
        loads = [path for kind, path in scene.log if kind == "set_object" and path in visuals]
        assert sorted(loads) == visuals, f"{name}: each mesh is sent once"
        assert max_pose_error(scene.transforms, expected) < POSE_TOLERANCE
    # The mesh files travel once per page: toby's objects refer to bob's.
    bob_link0 = scene.objects["/meshcat/armfleet/bob/visuals/bob_panda_link0_0"]["object"]
    toby_link0 = scene.objects["/meshcat/armfleet/toby/visuals/toby_panda_link0_0"]["object"]
    assert len(bob_link0["object"]["data"]) > 100_000
    assert toby_link0["object"]["data"] == ""
    assert toby_link0["object"]["armfleet_mesh"] == bob_link0["object"]["armfleet_mesh"]


def test_stage_has_a_grid_under_the_arms_and_a_camera_on_them(viewed: armfleet.World) -> None:
    with SceneWatcher(viewer_of(viewed).port) as watcher:
        scene = watcher.wait_quiet()
    grid = scene.objects["/meshcat/ground"]["object"]
    assert grid["object"]["type"] == "LineSegments"
    # The camera orbits the page's origin: the world is shifted to put the fleet there.
    target = -scene.transforms["/meshcat"][:3, 3]
    assert 0.0 < target[0] < 1.0 and abs(target[1]) < 0.3, "the camera aims between bob and toby"
    assert "/meshcat/origin" in scene.objects
    assert scene.properties[("/Grid", "visible")] is False  # MeshCat's own grid, replaced
    background = scene.properties[("/Background", "top_color")]
    assert min(background) < 0.9, "the background is not white"


# -- live updates ----------------------------------------------------------------------
def test_commanding_toby_moves_toby_not_bob(viewed: armfleet.World) -> None:
    bob, toby = viewed.arm("bob"), viewed.arm("toby")
    bob_before = expected_visual_poses(bob)
    with SceneWatcher(viewer_of(viewed).port) as watcher:
        watcher.wait_quiet()
        log_start = len(watcher.state.log)
        toby.move_to(nudge(toby, 0.4))
        settle(viewed, toby)
        toby_after = expected_visual_poses(toby)
        watcher.wait_for(lambda s: max_pose_error(s.transforms, toby_after) < POSE_TOLERANCE)
        scene = watcher.wait_quiet()
        moved = [path for kind, path in scene.log[log_start:] if kind == "set_transform"]
    assert any(path.startswith("/meshcat/armfleet/toby/visuals/") for path in moved)
    assert not any(path.startswith("/meshcat/armfleet/bob/") for path in moved)
    assert max_pose_error(scene.transforms, bob_before) < POSE_TOLERANCE


def test_target_marker_shows_where_toby_is_going(viewed: armfleet.World) -> None:
    toby = viewed.arm("toby")
    marker = "/meshcat/armfleet/toby/targets/tool0"
    target = nudge(toby, -0.3)
    with SceneWatcher(viewer_of(viewed).port) as watcher:
        toby.move_to(target)
        viewed.run(0.2)
        assert toby.is_moving
        goal = tool0_pose(toby, target)
        watcher.wait_for(
            lambda s: (
                s.properties.get((marker, "visible")) is True
                and marker in s.transforms
                and float(np.abs(s.transforms[marker] - goal).max()) < POSE_TOLERANCE
            )
        )
        settle(viewed, toby)
        watcher.wait_for(lambda s: s.properties.get((marker, "visible")) is False)
    assert np.abs(tool0_pose(toby)[:3, 3] - goal[:3, 3]).max() < 2e-3, "toby got there"


def test_landmark_frames_can_be_shown(viewed: armfleet.World) -> None:
    viewer = viewer_of(viewed)
    bob = viewed.arm("bob")
    with SceneWatcher(viewer.port) as watcher:
        # Hidden from the start (waited for: on a loaded machine a quiet moment can come
        # before the property is sent).
        watcher.wait_for(
            lambda s: s.properties.get(("/meshcat/armfleet/bob/landmarks", "visible")) is False
        )
        viewer.show_frames(True)
        watcher.wait_for(
            lambda s: s.properties[("/meshcat/armfleet/bob/landmarks", "visible")] is True
        )
        viewer.show_frames(False)
        scene = watcher.wait_quiet()
    tool0 = scene.transforms["/meshcat/armfleet/bob/landmarks/tool0"]
    assert np.abs(tool0 - tool0_pose(bob)).max() < POSE_TOLERANCE
    base = scene.transforms["/meshcat/armfleet/bob/landmarks/base_link"]
    assert np.abs(base[:3, 3]).max() < 1e-9  # bob's base_link is at the world origin
    assert scene.properties[("/meshcat/armfleet/bob/landmarks", "visible")] is False


@pytest.mark.parametrize(
    ("show", "expected"),
    [
        pytest.param(lambda v: v.show_frames("no"), "visible = 'no' is invalid",
                     id="show_frames('no') -> InvalidFlag, frames stay hidden"),
        pytest.param(lambda v: v.show_targets(0), "visible = 0 is invalid",
                     id="show_targets(0) -> InvalidFlag, markers stay shown"),
    ],
)  # fmt: skip
def test_show_takes_a_bool_only(viewed: armfleet.World, show: Any, expected: str) -> None:
    """'no' would have shown the frames: Python reads any text as yes."""
    viewer = viewer_of(viewed)
    with SceneWatcher(viewer.port) as watcher:
        before = watcher.wait_quiet().properties
        with pytest.raises(armfleet.InvalidFlag, match=expected):
            show(viewer)
        after = watcher.wait_quiet().properties
    for group in ("landmarks", "targets"):
        key = (f"/meshcat/armfleet/bob/{group}", "visible")
        assert after.get(key) == before.get(key)
    assert after.get(("/meshcat/armfleet/bob/landmarks", "visible")) is False


def test_display_updates_follow_wall_time_not_physics(viewed: armfleet.World) -> None:
    viewer = viewer_of(viewed)
    toby = viewed.arm("toby")
    toby.move_to(nudge(toby, 0.3))
    assert viewer.refresh()
    sent_before = viewer.batches_sent
    started = time.perf_counter()
    viewed.run(1.0)  # 1000 physics steps
    wall_s = time.perf_counter() - started
    assert viewer.refresh()
    sent = viewer.batches_sent - sent_before
    # One batch per display period at most, plus the final refresh and the idle one.
    assert 1 <= sent <= wall_s * DISPLAY_RATE_HZ + 3
    settle(viewed, toby)


def test_a_hung_browser_does_not_hold_up_the_others(viewed: armfleet.World) -> None:
    viewer = viewer_of(viewed)
    toby = viewed.arm("toby")
    hung = stalled_browser(viewer.port)
    try:
        with SceneWatcher(viewer.port) as watcher:
            for delta in (0.3, -0.3, 0.2):
                toby.move_to(nudge(toby, delta))
                settle(viewed, toby)
            assert viewer.refresh(), "the server still answers"
            final = expected_visual_poses(toby)
            watcher.wait_for(lambda s: max_pose_error(s.transforms, final) < POSE_TOLERANCE)
            loads = [path for kind, path in watcher.state.log if kind == "set_object"]
    finally:
        hung.close()
    # The watcher itself lagged while the first 20 MB of meshes went out: it caught
    # up on poses, and got every mesh once.
    assert len(loads) == len(set(loads))


def test_an_arm_appears_when_ready_and_goes_when_removed(viewed: armfleet.World) -> None:
    viewer = viewer_of(viewed)
    tim_node = "/meshcat/armfleet/tim"
    with SceneWatcher(viewer.port) as watcher:
        watcher.wait_quiet()
        tim = viewed.spawn("tim", at=(0, 1.2))
        expected = expected_visual_poses(tim)
        watcher.wait_for(lambda s: max_pose_error(s.transforms, expected) < POSE_TOLERANCE)
        assert len(watcher.state.nodes_under(f"{tim_node}/visuals")) == 11
        watcher.wait_for(lambda s: -s.transforms["/meshcat"][1, 3] > 0.3)  # reframed
        viewed.remove("tim")
        watcher.wait_for(lambda s: not s.nodes_under(tim_node))
        assert ("delete", tim_node) in watcher.state.log
        watcher.wait_for(lambda s: abs(s.transforms["/meshcat"][1, 3]) < 0.3)
    assert viewer.arms == ("bob", "toby")


def test_an_arm_is_framed_and_announced_before_its_meshes(viewed: armfleet.World) -> None:
    """The camera turns to a new arm and the loading line names it before its first mesh is
    sent; the line goes after its last mesh. Checked on the messages a page gets."""
    viewer = viewer_of(viewed)
    node = "/meshcat/armfleet/tia/visuals/"
    with SceneWatcher(viewer.port) as watcher:
        watcher.wait_quiet()
        start = len(watcher.state.log)
        viewed.spawn("tia", at=(0, 1.6))
        try:
            watcher.wait_for(lambda s: s.loading_lines[-1][1] == "")
            state = watcher.wait_quiet()
            meshes = [
                i for i, (kind, path) in enumerate(state.log)
                if kind == "set_object" and path.startswith(node)
            ]  # fmt: skip
            assert len(meshes) == 11
            # The stage's shift puts the framed box's middle at the page's origin: before
            # the first mesh it already holds tia's base (y = 1.6) in the framed box.
            shift = [m for i, m in state.shifts if start <= i < meshes[0]]
            assert shift and -shift[-1][1, 3] > 0.5, "reframed for tia before her meshes"
            lines = [(i, text) for i, text in state.loading_lines if i >= start]
            assert lines[0][0] < meshes[0]
            assert lines[0][1] == "loading the meshes of tia (arm 3 of 3)…"
            assert lines[-1] == (lines[-1][0], "") and lines[-1][0] > meshes[-1]
            assert viewer.loading_line == ""
        finally:
            viewed.remove("tia")


# -- replay ----------------------------------------------------------------------------
def replay_commands(path: Path) -> list[dict[str, Any]]:
    """The MeshCat commands a replay file runs, decoded."""
    html = path.read_text(encoding="utf-8")
    match = re.search(r'<script [^>]*id="armfleet-commands">(.*?)</script>', html)
    assert match is not None
    return [umsgpack.unpackb(base64.b64decode(c)) for c in json.loads(match.group(1))]


def test_replay_has_one_track_set_per_arm(viewed: armfleet.World, tmp_path: Path) -> None:
    toby = viewed.arm("toby")
    toby.move_to(nudge(toby, -0.25))
    settle(viewed, toby)
    path = viewer_of(viewed).save(tmp_path / "run.html")
    html = path.read_text(encoding="utf-8")
    assert "<script src" not in html and "http://" not in html.split("<script>", 1)[0]
    commands = replay_commands(path)
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    assert commands[-1] is animation
    by_arm: dict[str, dict[str, Any]] = {}
    for entry in animation["animations"]:
        arm = entry["path"].split("/")[3]
        by_arm.setdefault(arm, {})[entry["path"]] = entry["clip"]
    assert set(by_arm) == {"bob", "toby"}
    for name, clips in by_arm.items():
        # Arms appear when they are ready: bring-up takes simulated time.
        appear = clips.pop(f"/meshcat/armfleet/{name}")
        (visible,) = appear["tracks"]
        assert [k["value"] for k in visible["keys"]] == [False, True]
        visuals = set(expected_visual_poses(viewed.arm(name)))
        assert set(clips) == visuals | {f"/meshcat/armfleet/{name}/landmarks/tool0"}
        for clip in clips.values():
            tracks = {t["name"]: t for t in clip["tracks"]}
            assert set(tracks) == {".position", ".quaternion"}
    # The last key of toby's flange is where toby is now.
    flange = by_arm["toby"]["/meshcat/armfleet/toby/visuals/toby_panda_link7_0"]
    tracks = {t["name"]: t for t in flange["tracks"]}
    expected = expected_visual_poses(toby)["/meshcat/armfleet/toby/visuals/toby_panda_link7_0"]
    last_position = tracks[".position"]["keys"][-1]["value"]
    last_quaternion = tracks[".quaternion"]["keys"][-1]["value"]
    assert np.abs(np.array(last_position) - expected[:3, 3]).max() < 1e-6
    rotation = pin.Quaternion(np.array(last_quaternion)).toRotationMatrix()  # x, y, z, w
    assert np.abs(rotation - expected[:3, :3]).max() < 1e-6
    assert len(tracks[".position"]["keys"]) > 2, "toby's motion is in the replay"


def test_quaternions_match_pinocchio() -> None:
    pin.seed(7)
    rotations = np.array([pin.SE3.Random().rotation for _ in range(200)])
    # Half turns about each axis: the cases where w vanishes.
    rotations[:4] = [
        np.eye(3),
        np.diag([1.0, -1, -1]),
        np.diag([-1.0, 1, -1]),
        np.diag([-1.0, -1, 1]),
    ]
    rotations[4:8] = rotations[4:8] @ rotations[:4]
    ours = quaternions_xyzw(rotations)
    for rotation, quaternion in zip(rotations, ours, strict=True):
        assert abs(np.linalg.norm(quaternion) - 1.0) < 1e-12
        back = pin.Quaternion(quaternion).toRotationMatrix()
        assert np.abs(back - rotation).max() < 1e-9


# -- server process --------------------------------------------------------------------
def test_server_listens_on_loopback_only(viewed: armfleet.World) -> None:
    viewer = viewer_of(viewed)
    ports = {"web": viewer.port, "zmq": viewer.zmq_port}
    for port in ports.values():  # reachable on loopback
        socket.create_connection(("127.0.0.1", port), timeout=2.0).close()
    address = non_loopback_ipv4()
    if address is None:
        pytest.skip("this machine has no non-loopback IPv4 address to try")
    with socket.socket() as everywhere:  # control: the address reaches a listening socket
        everywhere.bind(("0.0.0.0", 0))
        everywhere.listen()
        socket.create_connection((address, everywhere.getsockname()[1]), timeout=2.0).close()
    for kind, port in ports.items():
        with pytest.raises(OSError):
            socket.create_connection((address, port), timeout=2.0).close()
            pytest.fail(f"the {kind} port {port} answers on {address}")


def test_server_answers_a_malformed_request_and_goes_on(viewed: armfleet.World) -> None:
    viewer = viewer_of(viewed)
    context = zmq.Context()
    connection = BridgeConnection(context, f"tcp://127.0.0.1:{viewer.zmq_port}", viewer.url)
    try:
        with pytest.raises(ViewerError, match="error"):
            connection.request([b"set_property", b"/meshcat/x", b"\xc1 not msgpack"])
        with pytest.raises(ViewerError, match="unknown request"):
            connection.request([b"launch_missiles"])
        assert connection.request([b"ping"]) == [b"ok"]
    finally:
        connection.close()
        context.destroy(linger=0)
    assert viewer.refresh()


def test_no_server_process_is_left_after_the_world_closes() -> None:
    world = armfleet.World(viewer=True)
    viewer = viewer_of(world)
    pid = viewer.server_pid
    assert process_alive(pid)
    world.close()
    assert not process_alive(pid)
    viewer.close()  # idempotent
    assert viewer.closed


def test_server_exits_when_the_python_process_is_killed(tmp_path: Path) -> None:
    script = textwrap.dedent(
        """
        import os, signal, sys
        import armfleet
        world = armfleet.World(viewer=True)
        print(world.viewer.server_pid, flush=True)
        sys.stdin.readline()
        os.kill(os.getpid(), signal.SIGKILL)  # no atexit, no close
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert child.stdout is not None and child.stdin is not None
    server_pid = int(child.stdout.readline())
    assert process_alive(server_pid)
    child.stdin.write("\n")
    child.stdin.flush()
    assert child.wait(10) == -signal.SIGKILL
    assert wait_until_gone(server_pid, 5.0), "the server outlived its parent"


def test_taken_port_leaves_the_world_running_without_viewer() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with armfleet.World(viewer=True, viewer_port=port) as world:
            assert world.viewer is None
            assert world.viewer_error is not None
            assert str(port) in world.viewer_error and "in use" in world.viewer_error
            bob = world.spawn("bob")
            target = nudge(bob, 0.2)
            bob.move_to(target)
            settle(world, bob)
            assert np.abs(bob.positions - target).max() < 1e-2


def test_a_dead_server_stops_the_viewer_not_the_simulation(tmp_path: Path) -> None:
    with armfleet.World(viewer=True) as world:
        viewer = viewer_of(world)
        bob = world.spawn("bob")
        os.kill(viewer.server_pid, signal.SIGKILL)
        bob.move_to(nudge(bob, 0.3))
        started = time.perf_counter()
        world.run(1.0)
        assert time.perf_counter() - started < 5.0, "stepping never waits for the viewer"
        deadline = time.monotonic() + 15.0
        while viewer.error is None and time.monotonic() < deadline:
            world.run(0.05)
        assert viewer.error is not None
        world.spawn("toby", at=(1, 0))  # add_arm on a stopped viewer: nothing happens
        assert viewer.arms == ("bob",)
        with pytest.raises(ViewerError, match="not running"):
            viewer.save(tmp_path / "run.html")
        assert isinstance(ViewerError("x"), armfleet.ArmfleetError)


# -- scene objects ---------------------------------------------------------------------
def test_objects_are_drawn_follow_the_physics_and_go_when_removed(tmp_path: Path) -> None:
    with armfleet.World(viewer=True) as world:
        viewer = viewer_of(world)
        world.add_object("table", "box", size=(0.4, 0.6, 0.3), mass=0, at=(0.6, 0, 0.15))
        can = world.add_object(
            "can", "cylinder", size=(0.03, 0.1), at=(0.6, 0, 0.5), color=(0, 0, 1, 0.5)
        )
        world.run(0.01)  # a frame of the replay with the can still in the air
        with SceneWatcher(viewer.port) as watcher:
            scene = watcher.wait_quiet()
            table = scene.objects["/meshcat/objects/table"]["object"]
            (box,) = table["geometries"]
            assert box["type"] == "BoxGeometry"
            assert [box[k] for k in ("width", "height", "depth")] == [0.4, 0.6, 0.3]
            can_object = scene.objects["/meshcat/objects/can"]["object"]
            (cylinder,), (paint,) = can_object["geometries"], can_object["materials"]
            assert (cylinder["type"], cylinder["height"]) == ("CylinderGeometry", 0.1)
            assert (paint["color"], paint["opacity"], paint["transparent"]) == (0x0000FF, 0.5, True)
            # MeshCat's cylinders stand along y: the node turns y onto the can's z.
            node = scene.transforms["/meshcat/objects/can"]
            assert np.abs(node[:3, 1] - can.pose[:3, 2]).max() < 1e-9
            world.run(1.0)  # the can falls onto the table
            assert can.position[2] == pytest.approx(0.35, abs=1e-3)
            watcher.wait_for(
                lambda s: abs(s.transforms["/meshcat/objects/can"][2, 3] - can.position[2]) < 1e-6
            )
            replay = viewer.save(tmp_path / "run.html")
            world.remove_object("can")
            watcher.wait_for(lambda s: "/meshcat/objects/can" not in s.objects)
            assert "/meshcat/objects/table" in watcher.state.objects
        assert viewer.objects == ("table",)
    (animation,) = [c for c in replay_commands(replay) if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    tracks = {t["name"]: t for t in clips["/meshcat/objects/can"]["tracks"]}
    heights = [key["value"][2] for key in tracks[".position"]["keys"]]
    assert heights[0] == pytest.approx(0.5, abs=1e-3) and heights[-1] == pytest.approx(
        0.35, abs=1e-3
    )
    quaternion = tracks[".quaternion"]["keys"][-1]["value"]
    rotation = pin.Quaternion(np.array(quaternion)).toRotationMatrix()
    assert np.abs(rotation[:, 1] - (0, 0, 1)).max() < 1e-3, "the can still stands in the replay"


@pytest.mark.parametrize(
    "positions, expected",
    [
        ({"bob": (0.0, float("nan"), 0.0)}, r"expected arm 'bob': give its base as three finite"),
        ({"bob": (0.0, 1.0)}, r"expected arm 'bob': give its base as three finite"),
        ([(0.0, 0.0, 0.0)], r"expected arms: give a mapping of arm name to base"),
    ],
)
def test_expected_arms_take_names_and_positions_only(
    viewed: armfleet.World, positions: Any, expected: str
) -> None:
    viewer = viewer_of(viewed)
    with pytest.raises(ViewerError, match=expected):
        viewer.expect_arms(positions)
    assert viewer.loading_line == "" and viewer.error is None
