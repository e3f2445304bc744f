"""The gripper, Cartesian goals, synchronised moves and objects through the live API: a real
client against a world running in another process."""

from __future__ import annotations

import re
import threading
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from armfleet.errors import NoGripper
from armfleet.messages import FloatArray, GripperMode, JointState
from armfleet.remote import Client, RemoteError
from tests.remote_world import WorldProcess, cli, wait_until
from tests.test_own_robot import UPSTREAM

#: Gripper widths are reached within 0.5 mm (the controller's own test: 0.2 mm).
WIDTH_TOLERANCE_M = 5e-4
#: Cartesian goals: the arm's IK solves to 1e-4; PD holding adds little.
REACHED_M, REACHED_RAD = 1e-3, 1e-3
HOLD_TOLERANCE_RAD = 2e-3


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    """Two Pandas facing each other 1.2 m apart and a UR3 (no gripper), in another process."""
    runtime = tmp_path_factory.mktemp("runtime")
    with WorldProcess(
        runtime, "bob", "toby", "ur", "--at", "0,0", "1.2,0,0,180", "0,1.2",
        "--model", "panda", "panda", "ur3", "--no-viewer", "--realtime",
    ) as process:  # fmt: skip
        yield process


@pytest.fixture
def client(world: WorldProcess) -> Iterator[Client]:
    with armfleet.connect(world.address) as connected:
        yield connected


def still_stepping(client: Client) -> bool:
    """The world's simulated time still advances (a wait, not a timing)."""
    start = client.info().time_s
    return wait_until(lambda: client.info().time_s > start + 0.01)


def home(client: Client, *names: str) -> None:
    """Send arms back to their home pose and wait there."""
    for name in names:
        arm = client.arm(name)
        arm.move_to(PANDA_HOME if arm.model == "panda" else arm.positions)
    for name in names:
        client.arm(name).wait()


PANDA_HOME = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]


def test_the_gripper_closes_on_nothing_and_reaches_widths(client: Client) -> None:
    bob = client.arm("bob")
    assert bob.has_gripper and bob.gripper.max_width == pytest.approx(0.08)
    bob.gripper.open()
    opened = bob.gripper.wait()
    assert opened.mode is GripperMode.AT_WIDTH
    assert abs(opened.width - 0.08) < WIDTH_TOLERANCE_M
    assert bob.gripper.close().mode is GripperMode.CLOSING
    closed = bob.gripper.wait()
    assert closed.mode is GripperMode.CLOSED and not closed.holding
    assert closed.width < 0.002 and not bob.gripper.holding
    for width in (0.03, 0.055):
        bob.gripper.move_to(width, force=20.0)
        reached = bob.gripper.wait()
        assert reached.mode is GripperMode.AT_WIDTH
        assert abs(reached.width - width) < WIDTH_TOLERANCE_M
    assert abs(bob.gripper.width - 0.055) < WIDTH_TOLERANCE_M
    described = client.call("arm", {"name": "bob"})["gripper"]
    assert described["mode"] == "at width" and described["holding"] is False


def test_a_revolute_jaw_is_gripped_in_radians_over_the_wire(
    client: Client, world: WorldProcess
) -> None:
    """SO-100 (a vendor file by path): its jaw's range and units reach the client and the
    CLI, and an angle below zero, valid for this jaw, is accepted and reached."""
    client.spawn("jaw", model=str(UPSTREAM["so100"]), at=(0.0, -1.2))
    try:
        gripper = client.arm("jaw").gripper
        jaw = ET.parse(UPSTREAM["so100"]).getroot().find("joint[@name='gripper']/limit")
        assert jaw is not None
        assert gripper.min_width == pytest.approx(float(jaw.get("lower", "nan")))
        assert gripper.max_width == pytest.approx(float(jaw.get("upper", "nan")))
        target = gripper.min_width / 2  # a negative angle
        assert target < 0.0
        gripper.move_to(target)
        reached = gripper.wait()
        assert reached.mode is GripperMode.AT_WIDTH
        assert abs(reached.width - target) < REACHED_RAD
        with pytest.raises(RemoteError, match=r"rad"):
            gripper.move_to(gripper.max_width + 1.0)
        gripped = cli(world.runtime_dir, "grip", "jaw", f"{target:.3f}", "--wait")
        assert gripped.returncode == 0, gripped.stderr
        shown = re.search(r"width (\S+) rad,", gripped.stdout)
        assert shown is not None, gripped.stdout
        assert abs(float(shown.group(1)) - target) < REACHED_RAD
        listed = cli(world.runtime_dir, "arms").stdout
        (row,) = [line for line in listed.splitlines() if line.startswith("jaw ")]
        assert "so100.urdf" in row and " rad at width" in row and "/" not in row.split()[1]
    finally:
        client.remove("jaw")


def test_a_model_without_fingers_has_no_gripper(client: Client) -> None:
    ur = client.arm("ur")
    assert not ur.has_gripper
    with pytest.raises(NoGripper, match=r"ur \(ur3\) has no gripper"):
        ur.gripper.close()
    # The world says the same to a client that asks it directly.
    with pytest.raises(RemoteError, match=r"ur \(ur3\) has no gripper") as refused:
        client.call("grip", {"name": "ur", "action": "close"})
    assert refused.value.kind == "NoGripper"
    assert client.call("arm", {"name": "ur"})["gripper"] is None


def pose_error(reached: FloatArray, wanted: FloatArray) -> tuple[float, float]:
    """(distance [m], angle [rad]) between two 4x4 poses."""
    error = pin.SE3(wanted).actInv(pin.SE3(reached))
    return float(np.linalg.norm(error.translation)), float(np.linalg.norm(pin.log3(error.rotation)))


def test_pose_goals_are_reached_within_1mm(client: Client) -> None:
    home(client, "bob")
    bob = client.arm("bob")
    start = client.lookup("world", "bob_tool0")
    goal = start.copy()
    goal[:3, 3] += (0.08, -0.05, -0.1)
    goal[:3, :3] = goal[:3, :3] @ pin.rpy.rpyToMatrix(0.0, 0.0, 0.4)
    assert bob.move_to_pose(goal) > 0.0
    bob.wait()
    distance, angle = pose_error(client.lookup("world", "bob_tool0"), goal)
    assert distance < REACHED_M and angle < REACHED_RAD
    # A position alone keeps the orientation; linear goes straight from where it is.
    oriented = client.lookup("world", "bob_tool0")
    bob.move_to_pose([0.45, 0.1, 0.35], linear=True)
    bob.wait()
    reached = client.lookup("world", "bob_tool0")
    assert np.linalg.norm(reached[:3, 3] - (0.45, 0.1, 0.35)) < REACHED_M
    turned = pin.log3(oriented[:3, :3].T @ reached[:3, :3])
    assert np.linalg.norm(turned) < REACHED_RAD
    # In another frame: toby's base, 1.2 m away facing bob (so x flips).
    bob.move_to_pose([0.8, 0.0, 0.45], "toby_base_link")
    bob.wait()
    seen_from_toby = client.lookup("toby_base_link", "bob_tool0")[:3, 3]
    assert np.linalg.norm(seen_from_toby - (0.8, 0.0, 0.45)) < REACHED_M
    assert np.linalg.norm(client.lookup("world", "bob_tool0")[:3, 3] - (0.4, 0.0, 0.45)) < (
        REACHED_M
    )


def test_an_unreachable_pose_is_refused_and_the_current_motion_goes_on(client: Client) -> None:
    home(client, "bob")
    bob = client.arm("bob")
    target = np.array(PANDA_HOME) + 0.3
    bob.move_to(target)
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)
    with pytest.raises(RemoteError, match=r"bob: tool0 cannot reach the pose") as refused:
        bob.move_to_pose(far)
    assert refused.value.kind == "UnreachablePose"
    final = bob.wait()
    assert np.abs(final.position[:7] - target).max() < HOLD_TOLERANCE_RAD


def motion_span(stamps: list[float], velocities: FloatArray, share: float) -> tuple[float, float]:
    """(first, last) stamp at which the fastest-moving joint goes faster than ``share`` of
    its peak speed: when a motion recorded as ``velocities`` (one row per stamp) starts
    and ends [s]."""
    speed = np.abs(velocities[:, int(np.argmax(np.abs(velocities).max(axis=0)))])
    moving = np.flatnonzero(speed > share * speed.max())
    return stamps[moving[0]], stamps[moving[-1]]


def test_move_together_starts_and_finishes_two_arms_together(client: Client) -> None:
    home(client, "bob", "toby")
    states: dict[str, list[JointState]] = {"bob": [], "toby": []}
    lock = threading.Lock()

    def keep(name: str) -> Callable[[JointState], None]:
        def append(state: JointState) -> None:
            with lock:
                states[name].append(state)

        return append

    subscriptions = [
        client.subscribe(f"/{name}/joint_states", keep(name), queue_size=10_000) for name in states
    ]
    # bob goes 1 rad, toby 0.1 rad: alone, toby would arrive long before bob.
    bob_target, toby_target = np.array(PANDA_HOME), np.array(PANDA_HOME)
    bob_target[0] += 1.0
    toby_target[0] += 0.1
    duration = client.move_together({"bob": bob_target, "toby": toby_target})
    final = {"bob": client.arm("bob").wait(), "toby": client.arm("toby").wait()}
    assert wait_until(
        lambda: all(states[n] and states[n][-1].stamp >= final[n].stamp for n in states)
    )
    for subscription in subscriptions:
        subscription.cancel()
    assert np.abs(final["bob"].position[:7] - bob_target).max() < HOLD_TOLERANCE_RAD
    assert np.abs(final["toby"].position[:7] - toby_target).max() < HOLD_TOLERANCE_RAD
    with lock:
        spans = {
            name: motion_span(
                [s.stamp for s in recorded], np.array([s.velocity[:7] for s in recorded]), 0.05
            )
            for name, recorded in states.items()
        }
    (bob_start, bob_end), (toby_start, toby_end) = spans["bob"], spans["toby"]
    # Both leave rest and come back to it within a tenth of the common duration of each
    # other (a long and a short jerk-limited profile pass 5 % of their peak speeds about
    # 0.05 T apart; unsynchronised, toby would stop some 0.6 T before bob).
    assert abs(bob_start - toby_start) < 0.1 * duration
    assert abs(bob_end - toby_end) < 0.1 * duration
    assert toby_end - toby_start > 0.8 * duration  # toby spread its 0.1 rad over all of it


def test_move_together_is_all_or_nothing(client: Client) -> None:
    home(client, "bob", "toby")
    before = {name: client.arm(name).positions for name in ("bob", "toby")}
    nan_target = [float("nan"), *PANDA_HOME[1:]]
    with pytest.raises(RemoteError, match=r"toby: target for toby_panda_joint1 is nan"):
        client.move_together({"bob": np.array(PANDA_HOME) + 0.2, "toby": nan_target})
    with pytest.raises(RemoteError, match=r"no arm named 'zed'; arms: bob, toby, ur"):
        client.move_together({"bob": np.array(PANDA_HOME) + 0.2, "zed": PANDA_HOME})
    with pytest.raises(RemoteError, match=r"'targets' is empty"):
        client.move_together({})
    assert still_stepping(client)
    for name, positions in before.items():
        arm = client.arm(name)
        assert not arm.is_moving
        assert np.abs(arm.positions - positions).max() < 1e-4


def test_objects_are_added_listed_and_removed(client: Client) -> None:
    added = client.add_object("crate", "box", size=(0.1, 0.2, 0.05), mass=0.4, at=(0.5, 0.6, 0.2))
    assert added.shape == "box" and added.size == (0.1, 0.2, 0.05) and added.mass == 0.4
    client.add_object("post", "cylinder", size=(0.03, 0.3), mass=0.0, at=(-0.6, 0.6, 0.15))
    assert list(client.objects) == ["crate", "post"]
    # The crate falls onto the ground and rests there, its centre 2.5 cm up; the post stays.
    assert wait_until(lambda: abs(client.objects["crate"].position[2] - 0.025) < 2e-3)
    assert client.objects["post"].static and client.objects["post"].position[2] == 0.15
    assert client.lookup("world", "crate")[2, 3] == pytest.approx(0.025, abs=2e-3)
    client.remove_object("crate")
    assert list(client.objects) == ["post"]
    with pytest.raises(RemoteError, match=r"no object named 'crate'; objects: post") as gone:
        client.remove_object("crate")
    assert gone.value.kind == "UnknownObject"
    client.remove_object("post")
    assert client.objects == {}


BAD_REQUESTS: dict[str, tuple[str, dict[str, Any], str]] = {
    "grip-unknown-arm": ("grip", {"name": "zed", "action": "open"}, "no arm named 'zed'"),
    "grip-action": (
        "grip",
        {"name": "bob", "action": "squeeze"},
        "action 'squeeze' is unknown; actions: open, close, width",
    ),
    "grip-no-width": ("grip", {"name": "bob", "action": "width"}, "missing field 'width'"),
    "grip-nan-width": (
        "grip",
        {"name": "bob", "action": "width", "width": float("nan")},
        "gripper width nan m is invalid; give a value in [0, 0.08] m",
    ),
    "grip-force": (
        "grip",
        {"name": "bob", "action": "close", "force": 1e6},
        "gripper force 1e+06 N is invalid; give a value in (0,",
    ),
    "pose-length": ("move_pose", {"name": "bob", "pose": [1.0, 2.0]}, "'pose' has 2 numbers"),
    "pose-missing": ("move_pose", {"name": "bob"}, "missing field 'pose'"),
    "pose-nan": (
        "move_pose",
        {"name": "bob", "position": [0.4, float("nan"), 0.4]},
        "a pose must be finite",
    ),
    "pose-not-rigid": (
        "move_pose",
        {"name": "bob", "pose": [2.0, 0, 0, 0.4, 0, 1, 0, 0, 0, 0, 1, 0.4, 0, 0, 0, 1]},
        "upper-left 3x3 must be a rotation",
    ),
    "pose-unknown-link": (
        "move_pose",
        {"name": "bob", "position": [0.4, 0, 0.4], "link": "hand"},
        "frame 'hand' not found; links of bob:",
    ),
    "pose-unknown-frame": (
        "move_pose",
        {"name": "bob", "position": [0.4, 0, 0.4], "frame": "nowhere"},
        "frame 'nowhere' not found",
    ),
    "together-not-numbers": (
        "move_together",
        {"targets": {"bob": ["a"]}},
        "'bob' must be a list of numbers",
    ),
    "object-mesh": (
        "add_object",
        {"name": "cup", "shape": "mesh", "size": 0.1},
        "shapes: box, cylinder, sphere",
    ),
    "object-size": (
        "add_object",
        {"name": "cup", "shape": "cylinder", "size": [0.1]},
        "size: got 1 numbers; a cylinder takes (radius, length)",
    ),
    "object-name": ("add_object", {"name": "bob", "shape": "sphere", "size": 0.1}, "'bob' is"),
    "object-field": (
        "add_object",
        {"name": "cup", "shape": "sphere", "size": 0.1, "colour": [1, 0, 0, 1]},
        "unknown field 'colour'",
    ),
}


@pytest.mark.parametrize("key", list(BAD_REQUESTS))
def test_a_bad_request_is_refused_and_the_world_goes_on(client: Client, key: str) -> None:
    op, args, says = BAD_REQUESTS[key]
    arms = {name: arm.positions for name, arm in client.arms.items()}
    with pytest.raises(RemoteError, match=None) as refused:
        client.call(op, args)
    assert says in str(refused.value)
    assert "\n" not in str(refused.value)
    assert still_stepping(client)
    assert client.objects == {}
    for name, positions in arms.items():
        assert np.abs(client.arm(name).positions - positions).max() < 1e-3
