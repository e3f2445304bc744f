"""Helpers of the viewer tests: a protocol-level scene client, expected poses, processes."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import functools
import os
import socket
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import umsgpack
from tornado.websocket import websocket_connect

import armfleet
from armfleet.messages import PlannedMotion

Matrix = np.ndarray


def ci_requires_browser() -> bool:
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


@contextlib.contextmanager
def headless_browser() -> Iterator[Any]:
    """Debian's Chromium, headless, launched by Playwright (never a downloaded browser).

    Skips the test when /usr/bin/chromium is missing on a developer machine; under CI a
    missing browser fails.
    """
    import pytest

    from armfleet.viewer.headless_chromium import CHROMIUM, CHROMIUM_FLAGS

    if not CHROMIUM.exists():
        if ci_requires_browser():
            pytest.fail(f"{CHROMIUM} is missing; the test command installs Debian's chromium")
        pytest.skip(f"{CHROMIUM} is missing (apt-get install chromium); CI does not skip this")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(
            executable_path=str(CHROMIUM), headless=True, args=list(CHROMIUM_FLAGS)
        )
        try:
            yield launched
        finally:
            launched.close()


@contextlib.contextmanager
def bob_and_toby_viewed() -> Iterator[armfleet.World]:
    """A world with a viewer, bob at (0, 0) and toby at (1, 0); closed on exit."""
    world = armfleet.World(viewer=True)
    try:
        assert world.viewer is not None, world.viewer_error
        world.spawn("bob", at=(0, 0))
        world.spawn("toby", at=(1, 0))
        yield world
    finally:
        world.close()


@functools.cache
def mesh_loader() -> Any:
    """Pinocchio reads a Panda's meshes in ~0.6 s: once for all tests."""
    import coal

    return coal.CachedMeshLoader()


def expected_visual_poses(arm: armfleet.Arm) -> dict[str, Matrix]:
    """World pose of each visual node of ``arm`` at its current positions, by MeshCat path.

    Computed here from the arm's URDF with Pinocchio, independently of the viewer.
    """
    model = arm.kinematics.model
    geometry = pin.buildGeomFromUrdfString(
        model, arm.description.urdf, pin.GeometryType.VISUAL, mesh_loader=mesh_loader()
    )
    data, geometry_data = model.createData(), pin.GeometryData(geometry)
    pin.updateGeometryPlacements(model, data, geometry, geometry_data, arm.body.position)
    return {
        f"/meshcat/armfleet/{arm.name}/visuals/{g.name}": geometry_data.oMg[i].homogeneous
        for i, g in enumerate(geometry.geometryObjects)
    }


def tool0_pose(arm: armfleet.Arm, arm_positions: Any = None) -> Matrix:
    """World pose of ``<arm>_tool0``, at ``arm_positions`` (arm joints) or where the arm is."""
    model = arm.kinematics.model
    q = arm.body.position.copy()
    if arm_positions is not None:
        q[arm.kinematics.arm_indices] = arm_positions
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    pose: Matrix = data.oMf[model.getFrameId(arm.description.tool0)].homogeneous
    return pose


def straight_plan(
    world: armfleet.World, arm: armfleet.Arm, goal: Any, waypoints: int = 25
) -> PlannedMotion:
    """The :class:`PlannedMotion` of a straight joint move of ``arm`` to ``goal`` from where
    its reference is, starting now: what the planner publishes for a path it found.

    Its tool path is computed here, independently of the viewer, by Pinocchio
    forward kinematics of the waypoints (:func:`tool0_pose`).
    """
    trajectory = arm.position_controller.trajectory
    assert trajectory is not None
    start = trajectory.position.copy()
    duration = arm.position_controller.plan(goal).duration
    share = np.linspace(0.0, 1.0, waypoints)
    positions = start + share[:, None] * (np.asarray(goal, dtype=float) - start)
    tool_path = np.array([tool0_pose(arm, q)[:3, 3] for q in positions])
    return PlannedMotion(
        world.time, arm.joint_names, tuple((share * duration).tolist()), positions, tool_path
    )


def start_planned_move(world: armfleet.World, arm: armfleet.Arm, goal: Any) -> PlannedMotion:
    """As the planner starts a plan: publish it on ``/<arm>/planned_motion``, then start the
    motion (here an ordinary ``move_to``, whose target is the plan's goal)."""
    plan = straight_plan(world, arm, goal)
    world.bus.publish(f"/{arm.name}/planned_motion", plan)
    arm.move_to(goal)
    return plan


def line_vertices(command: dict[str, Any]) -> np.ndarray:
    """The vertices (n x 3) of a MeshCat ``set_object`` of a line, as the page gets them."""
    geometry = command["object"]["geometries"][0]["data"]["attributes"]["position"]
    array = geometry["array"]
    data = array.data if isinstance(array, umsgpack.Ext) else np.asarray(array, np.float32)
    return np.frombuffer(bytes(data), dtype=np.float32).reshape(-1, geometry["itemSize"])


#: The longest a test waits for the viewer's messages to show an expected scene [s]: a cap
#: on an event, reached only when something is wrong (two cores shared by three pytest
#: workers made 10 s too short once).
EVENT_CAP_S = 60.0


@dataclass
class SceneState:
    """What a browser would show, rebuilt from the MeshCat commands it received."""

    objects: dict[str, dict[str, Any]] = field(default_factory=dict)
    transforms: dict[str, Matrix] = field(default_factory=dict)
    properties: dict[tuple[str, str], Any] = field(default_factory=dict)
    #: Every command received, in order, as (type, path).
    log: list[tuple[str, str]] = field(default_factory=list)
    #: The page's loading lines received, as (index in the log, text).
    loading_lines: list[tuple[int, str]] = field(default_factory=list)
    #: The transforms of ``/meshcat`` (the stage's shift) received, as (index in the log, matrix).
    shifts: list[tuple[int, Matrix]] = field(default_factory=list)

    def apply(self, command: dict[str, Any]) -> None:
        kind, path = command["type"], command.get("path", "")
        self.log.append((kind, path))
        if kind == "armfleet_status":
            self.loading_lines.append((len(self.log) - 1, command["text"]))
        elif kind == "set_transform" and path == "/meshcat":
            matrix = np.array(command["matrix"], dtype=float).reshape(4, 4).T
            self.shifts.append((len(self.log) - 1, matrix))
        if kind == "set_object":
            self.objects[path] = command
        elif kind == "set_transform":
            self.transforms[path] = np.array(command["matrix"], dtype=float).reshape(4, 4).T
        elif kind == "set_property":
            self.properties[(path, command["property"])] = command["value"]
        elif kind == "delete":
            for table in (self.objects, self.transforms):
                for key in [k for k in table if k == path or k.startswith(path + "/")]:
                    del table[key]

    def nodes_under(self, prefix: str) -> list[str]:
        return sorted(p for p in self.objects if p.startswith(prefix + "/"))


class SceneWatcher:
    """A websocket client of the viewer that keeps the scene it is sent (a browser minus WebGL).

    Args:
        port: the viewer's web port.
    """

    def __init__(self, port: int) -> None:
        self._port = port
        self._state = SceneState()
        self._lock = threading.Lock()
        self._last_message = time.monotonic()
        self._stop = threading.Event()
        self._connected = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> SceneWatcher:
        self._thread.start()
        if not self._connected.wait(EVENT_CAP_S):
            raise RuntimeError(f"no websocket connection: {self._error}")
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(5.0)

    def _run(self) -> None:
        try:
            asyncio.run(self._read())
        except BaseException as exc:
            self._error = exc
            self._connected.set()

    async def _read(self) -> None:
        url = f"ws://127.0.0.1:{self._port}/"
        connection = await websocket_connect(url, max_message_size=512 * 2**20)
        self._connected.set()
        while not self._stop.is_set():
            try:
                message = await asyncio.wait_for(connection.read_message(), 0.1)
            except asyncio.TimeoutError:
                continue
            if message is None:
                return
            assert isinstance(message, bytes)
            decoded = umsgpack.unpackb(message)
            with self._lock:  # live updates come as arrays of commands
                for command in decoded if isinstance(decoded, list) else [decoded]:
                    self._state.apply(command)
                self._last_message = time.monotonic()
        connection.close()

    @property
    def state(self) -> SceneState:
        return self._state

    def wait_quiet(self, quiet_s: float = 0.5, timeout_s: float = 20.0) -> SceneState:
        """Wait until no message came for ``quiet_s``; returns the scene."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self._lock:
                if time.monotonic() - self._last_message > quiet_s:
                    return self._state
            time.sleep(0.05)
        raise AssertionError(f"the viewer kept sending for {timeout_s} s")

    def wait_for(
        self, predicate: Callable[[SceneState], bool], timeout_s: float = EVENT_CAP_S
    ) -> None:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self._lock:
                if predicate(self._state):
                    return
            time.sleep(0.02)
        raise AssertionError(f"the scene did not reach the expected state in {timeout_s} s")


def stalled_browser(port: int) -> socket.socket:
    """A websocket that opens and then never reads: a browser that hangs."""
    connection = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    connection.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    connection.connect(("127.0.0.1", port))
    key = base64.b64encode(os.urandom(16)).decode()
    connection.sendall(
        (
            f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        ).encode()
    )
    response = b""
    while b"\r\n\r\n" not in response:
        response += connection.recv(1)
    assert response.startswith(b"HTTP/1.1 101"), response
    return connection


def process_alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting to be reaped counts as ended)."""
    stat = Path(f"/proc/{pid}/stat")
    if stat.parent.parent.joinpath("self").exists():
        try:
            state = stat.read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return False
        return state not in ("Z", "X")
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def wait_until_gone(pid: int, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if not process_alive(pid):
            return True
        time.sleep(0.05)
    return not process_alive(pid)


def non_loopback_ipv4() -> str | None:
    """An IPv4 address of this machine other than 127.x, or None if it has none."""
    candidates: set[str] = set()
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.connect(("192.0.2.1", 9))  # TEST-NET-1: no packet is sent for UDP connect
        candidates.add(probe.getsockname()[0])
    except OSError:
        pass
    finally:
        probe.close()
    try:
        for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET):
            candidates.add(str(info[4][0]))
    except OSError:
        pass
    usable = sorted(a for a in candidates if not a.startswith("127.") and a != "0.0.0.0")
    return usable[0] if usable else None
