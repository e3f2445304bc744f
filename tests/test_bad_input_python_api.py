"""Bad types and time steps through the Python API (issue #14, items 4 and 8).

Every number a user gives goes through one rule (:mod:`armfleet.checks.real_numbers`): text,
bool, complex and None are not numbers, even where ``float()`` would take them. Each
case below is one class of bad input; it must raise its own :class:`ArmfleetError`
subclass with a one-line message naming the argument and what is valid, and leave the
world untouched (``check_rejected`` of ``test_bad_input``: same arms, bodies, time and
reference, nothing commanded, bob still holding within 1e-4 rad), nor command the
gripper.

The step ``dt`` has one range for :class:`armfleet.World` and launch specs
(:mod:`armfleet.checks.time_step`); at its top every shipped model still brings up and meets
issue #2's tracking figures.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from armfleet.checks.time_step import MAX_DT_S, MIN_DT_S
from armfleet.description import ModelLibrary
from armfleet.errors import (
    ArmfleetError,
    InvalidFlag,
    InvalidNumber,
    ObjectError,
    ParameterError,
    PoseError,
    TargetPoseError,
    TargetTypeError,
    UnknownFrame,
)
from armfleet.messages import ArmMode, FloatArray, GripperCommand
from armfleet.recording import RecordingError
from armfleet.remote import RemoteError, serve
from armfleet.remote.remote_arm import RemoteArm
from armfleet.spec import SpecError, parse_spec
from tests.test_bad_input import (  # noqa: F401  (scene: a fixture)
    BadInput,
    Scene,
    check_rejected,
    scene,
)
from tests.test_remote_python_server import Served, served  # noqa: F401  (served: a fixture)

#: issue #2's tracking figures: during a motion, and 0.2 s after it ended [rad].
MAX_TRACKING_ERROR_RAD = 1e-3
FINAL_ERROR_RAD = 1e-4
SETTLE_S = 0.2
ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")


def tool0(world: armfleet.World) -> FloatArray:
    return world.tf.lookup("world", "bob_tool0")


def nan_se3(world: armfleet.World, bob: armfleet.Arm) -> pin.SE3:
    pose = tool0(world)
    goal = pin.SE3(pose[:3, :3].copy(), pose[:3, 3].copy())
    goal.translation = np.array([math.nan, 0.0, 0.5])
    return goal


def stretched_se3(world: armfleet.World, bob: armfleet.Arm) -> pin.SE3:
    """bob's own tool pose with its rotation scaled by 1.5: not a rotation."""
    pose = tool0(world)
    return pin.SE3(1.5 * pose[:3, :3], pose[:3, 3].copy())


def as_text(values: object) -> list[str]:
    return [str(float(v)) for v in np.asarray(values).reshape(-1)]


def write_mesh(name: str, text: str) -> str:
    """A mesh file in the test's own folder (the test runs in ``tmp_path``)."""
    Path(name).write_text(text)
    return name


def case(action: object, error: type[ArmfleetError], *expected: str, id: str) -> object:
    return pytest.param(BadInput(action, error, lambda w, b: expected), id=id)  # type: ignore[arg-type]


JOINTS = "one per joint: bob_panda_joint1"
SPAWN_TOBY = {"name": "toby", "at": (1, 0)}

CASES = [
    # -- joint targets: move_to, move_together, IK seeds, initial positions ----------
    case(
        lambda w, b: b.move_to(as_text(b.positions)),
        TargetTypeError, "bob: targets must be numbers", JOINTS,
        id="move_to numeric strings -> TargetTypeError",
    ),
    case(
        lambda w, b: b.move_to(np.asarray(b.positions, dtype=complex) + 1e-3j),
        TargetTypeError, "bob: targets must be numbers", JOINTS,
        id="move_to a complex array -> TargetTypeError, not its real part",
    ),
    case(
        lambda w, b: b.move_to([False] * 7),
        TargetTypeError, "bob: targets must be numbers", JOINTS,
        id="move_to bools -> TargetTypeError",
    ),
    case(
        lambda w, b: b.move_to(None),
        TargetTypeError, "bob: targets must be numbers", JOINTS,
        id="move_to None -> TargetTypeError",
    ),
    case(
        lambda w, b: w.move_together({"bob": as_text(b.positions)}),
        TargetTypeError, "bob: targets must be numbers", JOINTS,
        id="move_together numeric strings -> TargetTypeError",
    ),
    case(
        lambda w, b: w.move_together([("bob", b.positions)]),
        ArmfleetError, "move_together takes a mapping {arm name: target}", "got list",
        id="move_together a list -> ArmfleetError asking for a mapping",
    ),
    case(
        lambda w, b: b.solve_ik(tool0(w), seed=as_text(b.positions)),
        TargetTypeError, "bob: targets must be numbers", JOINTS,
        id="solve_ik seed numeric strings -> TargetTypeError",
    ),
    case(
        lambda w, b: w.spawn(**SPAWN_TOBY, initial_positions=as_text(b.positions)),
        TargetTypeError, "toby: targets must be numbers", "toby_panda_joint1",
        id="spawn initial_positions numeric strings -> TargetTypeError",
    ),
    # -- Cartesian goals ----------------------------------------------------------------
    case(
        lambda w, b: b.move_to_pose(stretched_se3(w, b)),
        TargetPoseError, "must be a rotation (orthonormal, det +1)",
        id="move_to_pose SE3 with a non-orthonormal rotation -> TargetPoseError",
    ),
    case(
        lambda w, b: b.move_to_pose(nan_se3(w, b), linear=True),
        TargetPoseError, "finite",
        id="move_to_pose NaN SE3 linear -> TargetPoseError, not ValueError",
    ),
    case(
        lambda w, b: b.move_to_pose(nan_se3(w, b)),
        TargetPoseError, "finite",
        id="move_to_pose NaN SE3 -> TargetPoseError, not an unreachable nan residual",
    ),
    case(
        lambda w, b: b.move_to_pose([as_text(row) for row in tool0(w)]),
        TargetPoseError, "4x4 homogeneous matrix of numbers",
        id="move_to_pose matrix of numeric strings -> TargetPoseError",
    ),
    case(
        lambda w, b: b.move_to_pose(tool0(w), link=7),
        UnknownFrame, "frame 7 not found", "links of bob:", "tool0",
        id="move_to_pose link not a string -> UnknownFrame listing the links",
    ),
    # -- yes/no flags: a bool, not whatever Python reads as true (armfleet.checks.flags) ----------
    case(
        lambda w, b: b.move_to_pose(tool0(w), linear="no"),
        InvalidFlag, "linear = 'no' is invalid; give True or False",
        id="move_to_pose linear='no' -> InvalidFlag, not a straight-line move",
    ),
    case(
        lambda w, b: b.move_to_pose(tool0(w), linear=1),
        InvalidFlag, "linear = 1 is invalid; give True or False",
        id="move_to_pose linear=1, a number as a flag -> InvalidFlag",
    ),
    case(
        lambda w, b: b.move_to_pose(tool0(w), linear=None),
        InvalidFlag, "linear = None is invalid; give True or False",
        id="move_to_pose linear=None -> InvalidFlag, not a joint-space move",
    ),
    case(
        lambda w, b: w.run(0.01, realtime="no"),
        InvalidFlag, "realtime = 'no' is invalid; give True or False",
        id="run realtime='no' -> InvalidFlag before any step",
    ),
    case(
        lambda w, b: w.bus.publish("/probe", "hello", latch="no"),
        InvalidFlag, "latch = 'no' is invalid; give True or False",
        id="bus.publish latch='no' -> InvalidFlag, nothing latched or delivered",
    ),
    # -- stamps: the number rule ------------------------------------------------------------
    case(
        lambda w, b: b.status("1"),
        InvalidNumber, "bob: stamp = '1' is invalid", "a time >= 0 s",
        id="status stamp '1' -> InvalidNumber, not a status stamped with text",
    ),
    case(
        lambda w, b: b.status(None),
        InvalidNumber, "bob: stamp = None is invalid",
        id="status stamp None -> InvalidNumber",
    ),
    case(
        lambda w, b: b.status(math.nan),
        InvalidNumber, "bob: stamp = nan is invalid",
        id="status stamp nan -> InvalidNumber",
    ),
    case(
        lambda w, b: b.gripper.state("0"),
        InvalidNumber, "bob: gripper stamp = '0' is invalid", "a time >= 0 s",
        id="gripper.state stamp '0' -> InvalidNumber",
    ),
    # -- gripper --------------------------------------------------------------------------
    case(
        lambda w, b: b.gripper.move_to("0.04"),
        InvalidNumber, "bob: gripper width = '0.04' is invalid", "[0, 0.08] m",
        id="gripper width '0.04' -> InvalidNumber",
    ),
    case(
        lambda w, b: b.gripper.move_to(None),
        InvalidNumber, "bob: gripper width = None is invalid", "[0, 0.08] m",
        id="gripper width None -> InvalidNumber, not TypeError",
    ),
    case(
        lambda w, b: b.gripper.move_to(True),
        InvalidNumber, "bob: gripper width = True is invalid",
        id="gripper width a bool -> InvalidNumber",
    ),
    case(
        lambda w, b: b.gripper.close("10"),
        InvalidNumber, "bob: gripper force = '10' is invalid", "(0, ",
        id="gripper force '10' -> InvalidNumber",
    ),
    # -- running, recording --------------------------------------------------------------
    case(
        lambda w, b: w.run("1"),
        InvalidNumber, "duration = '1' is invalid", "seconds in [0, 1000000]",
        id="run '1' -> InvalidNumber, not TypeError",
    ),
    case(
        lambda w, b: w.run(True),
        InvalidNumber, "duration = True is invalid",
        id="run True -> InvalidNumber, not one second of simulation",
    ),
    case(
        lambda w, b: w.run(None),
        InvalidNumber, "duration = None is invalid",
        id="run None -> InvalidNumber, not TypeError",
    ),
    case(
        lambda w, b: w.run(1e308),
        InvalidNumber, "duration = 1e+308 is invalid", "seconds in [0, 1000000]",
        id="run 1e308 s -> InvalidNumber, not OverflowError",
    ),
    case(
        lambda w, b: w.record(5),
        RecordingError, "recording 5", ".mcap",
        id="record to a path that is a number -> RecordingError, not TypeError",
    ),
    case(
        lambda w, b: w.record("run.mcap", topics="/bob/*"),
        RecordingError, "topics='/bob/*' must be a list",
        id="record topics as one string -> RecordingError, not one pattern per letter",
    ),
    case(
        lambda w, b: w.record("run.mcap", spec="bob_and_toby"),
        RecordingError, "spec must be an armfleet.FleetSpec", "got str",
        id="record spec a name, not a FleetSpec -> RecordingError, not AttributeError",
    ),
    case(
        lambda w, b: w.submit(5),
        ArmfleetError, "submit takes a function of no arguments, got int",
        id="submit a non-function -> ArmfleetError, not TypeError from the stepping thread",
    ),
    # -- spawn ------------------------------------------------------------------------------
    case(
        lambda w, b: w.spawn("toby", at=None),
        PoseError, "spawn pose None must be (x, y[, z[, yaw_deg]]) of numbers",
        id="spawn at None -> PoseError, not TypeError",
    ),
    case(
        lambda w, b: w.spawn("toby", at=("1", "0")),
        PoseError, "spawn pose ('1', '0') must be (x, y[, z[, yaw_deg]]) of numbers",
        id="spawn at numeric strings -> PoseError",
    ),
    case(
        lambda w, b: w.spawn("toby", at=(True, False)),
        PoseError, "of numbers",
        id="spawn at bools -> PoseError",
    ),
    case(
        lambda w, b: w.spawn(**SPAWN_TOBY, parameter_files="position_controller.yaml"),
        ParameterError, "parameter_files must be a mapping", "got str", "position_controller",
        id="spawn parameter_files a string path -> ParameterError asking for a mapping",
    ),
    case(
        lambda w, b: w.spawn(**SPAWN_TOBY, parameter_files={"position_controller": 5}),
        ParameterError, "parameter_files['position_controller'] must be the path", "got int 5",
        id="spawn parameter_files path not a path -> ParameterError, not AttributeError",
    ),
    case(
        lambda w, b: w.spawn(**SPAWN_TOBY, parameters="kp_s2=900"),
        ParameterError, "parameters must be a mapping", "got str",
        id="spawn parameters a string -> ParameterError asking for a mapping",
    ),
    # -- objects ------------------------------------------------------------------------------
    case(
        lambda w, b: w.add_object("crate", "box", size=("0.1", 0.1, 0.1), at=(2, 2, 0.05)),
        ObjectError, "object 'crate': size:", "is not numbers",
        id="add_object size numeric strings -> ObjectError",
    ),
    case(
        lambda w, b: w.add_object("crate", "box", size=(0.1, 0.1, 0.1), at=("2", 2, 0.05)),
        ObjectError, "object 'crate': at: expected 3 numbers",
        id="add_object at numeric strings -> ObjectError",
    ),
    case(
        lambda w, b: w.add_object("blob", "mesh", mesh=5, at=(2, 2, 0.5)),
        ObjectError, "object 'blob': mesh: 5 is not a path", ".obj/.stl",
        id="add_object mesh path a number -> ObjectError, not TypeError",
    ),
    case(
        lambda w, b: w.add_object(
            "blob", "mesh", mesh=write_mesh("point.obj", "v 0 0 0\n"), at=(2, 2, 0.5)
        ),
        ObjectError, "object 'blob': mesh:", "no face with an area",
        id="add_object mesh of a single vertex -> ObjectError, not pybullet.error",
    ),
    case(
        lambda w, b: w.add_object(
            "blob", "mesh", mesh=write_mesh("dot.obj", "v 0 0 0\nf 1 1 1\n"), at=(2, 2, 0.5)
        ),
        ObjectError, "object 'blob': mesh:", "no face with an area",
        id="add_object mesh whose only face is a point -> ObjectError, not a 0 m object",
    ),
    case(
        lambda w, b: w.add_object(
            "blob",
            "mesh",
            mesh=write_mesh("plate.obj", "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n"),
            at=(2, 2, 0.5),
        ),
        ObjectError, "object 'blob': mesh: plate.obj is flat", "mass=0",
        id="add_object flat mesh that would move -> ObjectError naming mass=0",
    ),
]  # fmt: skip


@pytest.fixture(autouse=True)
def in_tmp_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Mesh files and recordings a case writes go to the test's own folder."""
    monkeypatch.chdir(tmp_path)


@pytest.mark.parametrize("bad", CASES)
def test_bad_types_are_refused_in_one_line_and_the_world_untouched(
    scene: Scene,  # noqa: F811
    bad: BadInput,
) -> None:
    gripper_commands: list[GripperCommand] = []
    scene.world.bus.subscribe("/bob/gripper_controller/commands", gripper_commands.append)
    objects, width = list(scene.world.objects), scene.bob.gripper.width
    check_rejected(scene, bad)
    assert gripper_commands == []
    assert list(scene.world.objects) == objects
    assert not list(Path().glob("*.mcap"))  # a refused recording leaves no file
    # The fingers did not move either (they hold their width within 0.1 mm).
    assert abs(scene.bob.gripper.width - width) < 1e-4


@pytest.mark.parametrize(
    ("arguments", "expected"),
    [
        pytest.param({"dt": "0.001"}, "dt = '0.001' is invalid", id="dt '0.001' -> InvalidNumber"),
        pytest.param({"dt": True}, "dt = True is invalid", id="dt True -> InvalidNumber"),
        pytest.param(
            {"dt": 1e-9}, "dt = 1e-09 is invalid", id="dt 1e-9, below 1e-5 s -> InvalidNumber"
        ),
        pytest.param(
            {"dt": 0.1}, "dt = 0.1 is invalid", id="dt 0.1, too coarse to track -> InvalidNumber"
        ),
        pytest.param({"dt": math.nan}, "dt = nan is invalid", id="dt nan -> InvalidNumber"),
        pytest.param(
            {"gravity": "9.81"}, "gravity = '9.81' is invalid", id="gravity '9.81' -> InvalidNumber"
        ),
        pytest.param(
            {"viewer": True, "viewer_port": "8080"},
            "viewer_port = '8080' is invalid",
            id="viewer_port '8080' -> InvalidNumber before any viewer starts",
        ),
    ],
)
def test_bad_world_settings_are_refused_before_any_world_exists(
    arguments: dict[str, object], expected: str
) -> None:
    with pytest.raises(InvalidNumber) as caught:
        armfleet.World(**arguments)  # type: ignore[arg-type]
    message = str(caught.value)
    assert "\n" not in message
    assert expected in message
    valid = {
        "dt": f"[1e-05, {MAX_DT_S:g}] s",
        "gravity": "[-100, 100] m/s^2",
        "viewer_port": "a TCP port, an integer in 1..65535",
    }
    assert valid[next(key for key in valid if key in arguments)] in message


def launch_bob(viewer: object) -> object:
    return armfleet.launch("bob_and_toby", viewer=viewer)  # type: ignore[arg-type]


def start_viewer(**flags: object) -> object:
    from armfleet.viewer import Viewer

    return Viewer(**flags)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("start", "expected"),
    [
        pytest.param(
            lambda: armfleet.World(viewer="no"),  # type: ignore[arg-type]
            "viewer = 'no' is invalid",
            id="World viewer='no' -> InvalidFlag, not a viewer started",
        ),
        pytest.param(
            lambda: armfleet.World(viewer=0),  # type: ignore[arg-type]
            "viewer = 0 is invalid",
            id="World viewer=0, a number as a flag -> InvalidFlag",
        ),
        pytest.param(
            lambda: launch_bob("False"), "viewer = 'False' is invalid",
            id="launch viewer='False' -> InvalidFlag before the scene is rehearsed",
        ),
        pytest.param(
            lambda: start_viewer(show_frames="no"), "show_frames = 'no' is invalid",
            id="Viewer show_frames='no' -> InvalidFlag before its server starts",
        ),
        pytest.param(
            lambda: start_viewer(show_targets=None), "show_targets = None is invalid",
            id="Viewer show_targets=None -> InvalidFlag before its server starts",
        ),
    ],
)  # fmt: skip
def test_bad_flags_are_refused_before_anything_starts(
    start: Callable[[], object], expected: str
) -> None:
    with pytest.raises(InvalidFlag) as caught:
        start()
    message = str(caught.value)
    assert "\n" not in message
    assert expected in message and message.endswith("give True or False")


def test_serve_register_no_is_refused_and_names_no_world(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """serve(world, register='no') would write the runtime file every client joins."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    refused = r"^register = 'no' is invalid; give True or False$"
    with armfleet.World() as world, pytest.raises(InvalidFlag, match=refused):
        serve(world, register="no")  # type: ignore[arg-type]
    assert not list(tmp_path.rglob("*.json"))  # no world named for clients to join


def test_a_numpy_bool_is_a_flag(scene: Scene) -> None:  # noqa: F811
    """np.True_ (what a comparison of arrays gives) counts: bob goes in a straight line.

    Checked against the geometry: halfway through the motion the tool is on the segment
    from start to goal within 1 mm. (A guard: NumPy bools were taken before too.)
    """
    world, bob = scene.world, scene.bob
    start = tool0(world)
    goal = start.copy()
    goal[1, 3] += 0.15
    duration = bob.move_to_pose(goal, linear=np.bool_(True))  # type: ignore[arg-type]
    world.run(duration / 2)
    middle = tool0(world)[:3, 3]
    a, b = start[:3, 3], goal[:3, 3]
    along = np.clip(np.dot(middle - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    assert np.linalg.norm(middle - (a + along * (b - a))) < 1e-3  # [m]
    assert 0.2 < along < 0.8  # really on its way
    world.run(duration / 2 + 0.5)
    assert np.abs(tool0(world)[:3, 3] - b).max() < 1e-3  # arrived [m]


class ArrayLike:
    """Numbers behind ``__array__`` (as a tensor or a pandas Series has), not a sequence."""

    def __init__(self, values: FloatArray) -> None:
        self._values = values

    def __array__(self, *args: object, **kwargs: object) -> FloatArray:
        return self._values  # NumPy casts it if asked for another dtype


def test_numbers_in_an_array_like_are_still_numbers(scene: Scene) -> None:  # noqa: F811
    """The rule refuses text and bools, not containers: bob goes where an array-like says."""
    world, bob = scene.world, scene.bob
    target = bob.positions
    target[0] += 0.1
    assert bob.move_to(ArrayLike(target)) > 0.0  # type: ignore[arg-type]
    world.run(1.0)
    assert np.abs(bob.positions - target).max() < 1e-3  # arrived [rad]
    with pytest.raises(TargetTypeError):
        bob.move_to(ArrayLike(np.array(as_text(target))))  # type: ignore[arg-type]


def test_a_model_library_that_is_not_one_is_refused() -> None:
    with pytest.raises(
        ArmfleetError, match=r"models must be an armfleet\.description\.ModelLibrary"
    ):
        armfleet.World(models="description/")  # type: ignore[arg-type]


def spec_with_dt(dt: float) -> str:
    # As the messages print it: "1e-05", which YAML 1.1 alone would read as text.
    return f"world:\n  dt_s: {dt:g}\narms:\n  - name: bob\n    model: panda\n"


def test_world_and_spec_take_the_same_steps() -> None:
    """One range: the bounds are valid for both, just outside them neither, written in a
    spec as the error message prints them."""
    for dt in (MIN_DT_S, MAX_DT_S):
        assert parse_spec(spec_with_dt(dt), "inline").world.dt_s == dt
        with armfleet.World(dt=dt) as world:
            assert world.dt == dt
    for dt in (MIN_DT_S * 0.9, MAX_DT_S * 1.1):
        with pytest.raises(SpecError, match=r"world\.dt_s: .* outside \[1e-05, 0\.002\]"):
            parse_spec(spec_with_dt(dt), "inline")
        with pytest.raises(InvalidNumber, match=r"dt = .* give a step in \[1e-05, 0\.002\] s"):
            armfleet.World(dt=dt)


def test_cli_launch_check_refuses_a_coarse_dt(tmp_path: Path) -> None:
    spec = tmp_path / "coarse.yaml"
    spec.write_text(spec_with_dt(0.005))
    env = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}
    done = subprocess.run(
        [*ARMFLEET, "launch", str(spec), "--check"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert "coarse.yaml:2: world.dt_s: 0.005 is outside [1e-05, 0.002] [s]" in lines[0]


@pytest.mark.parametrize("model", ModelLibrary().names)
def test_every_shipped_model_tracks_at_the_largest_dt(model: str) -> None:
    """At MAX_DT_S a model brings up, follows a +0.3 rad move of every joint within issue
    #2's 1e-3 rad and settles within 1e-4 rad of its target 0.2 s after the motion.

    (Measured when the bound was set: a Panda at 2.2 ms settles 2e-4 rad off target, and
    from 4.6 ms does not bring up.)
    """
    with armfleet.World(dt=MAX_DT_S) as world:
        arm = world.spawn("bob", model=model)
        lower, upper = arm.joint_limits
        target = np.clip(arm.positions + 0.3, lower + 0.05, upper - 0.05)
        arm.move_to(target)
        worst, deadline = 0.0, world.time + 10.0
        while arm.is_moving and world.time < deadline:
            world.step()
            trajectory = arm.position_controller.trajectory
            assert trajectory is not None
            worst = max(worst, float(np.abs(trajectory.position - arm.positions).max()))
        assert not arm.is_moving
        world.run(SETTLE_S)
        assert worst < MAX_TRACKING_ERROR_RAD
        assert np.abs(arm.positions - target).max() < FINAL_ERROR_RAD


# -- the same through the live-API client ---------------------------------------------------
RemoteUse = Callable[[RemoteArm], object]

REMOTE_CASES = [
    pytest.param(
        lambda b: b.move_to(as_text(b.positions)), ArmfleetError, "bob: targets must be numbers",
        id="remote move_to numeric strings -> refused before sending",
    ),
    pytest.param(
        lambda b: b.move_to([False] * 7), ArmfleetError, "bob: targets must be numbers",
        id="remote move_to bools -> refused before sending",
    ),
    pytest.param(
        lambda b: b.move_to_pose([["1"] * 4] * 4), ArmfleetError, "a pose must be a 4x4 matrix",
        id="remote move_to_pose matrix of strings -> refused before sending",
    ),
    pytest.param(
        lambda b: b.gripper.move_to("0.04"), InvalidNumber,
        "bob: gripper width = '0.04' is invalid",
        id="remote gripper width '0.04' -> InvalidNumber before sending",
    ),
    pytest.param(
        lambda b: b.gripper.move_to(None), InvalidNumber, "bob: gripper width = None is invalid",
        id="remote gripper width None -> InvalidNumber, not TypeError",
    ),
    pytest.param(
        lambda b: b.gripper.close("10"), InvalidNumber, "bob: gripper force = '10' is invalid",
        id="remote gripper force '10' -> InvalidNumber before sending",
    ),
    pytest.param(
        lambda b: b.move_to_pose([0.4, 0.0, 0.4], linear="no"), InvalidFlag,
        "linear = 'no' is invalid; give True or False",
        id="remote move_to_pose linear='no' -> InvalidFlag before sending",
    ),
]  # fmt: skip


@pytest.mark.parametrize(("use", "error", "expected"), REMOTE_CASES)
def test_the_live_api_client_refuses_the_same_types(
    served: Served,  # noqa: F811
    use: RemoteUse,
    error: type[ArmfleetError],
    expected: str,
) -> None:
    world = served.world
    sent: list[object] = []
    world.bus.subscribe("/bob/position_controller/commands", sent.append)
    world.bus.subscribe("/bob/gripper_controller/commands", sent.append)
    served.step_in_background()
    with armfleet.connect(served.server.address) as client:
        bob = client.arm("bob")
        with pytest.raises(error) as caught:
            use(bob)
        assert type(caught.value) is error
        assert expected in str(caught.value) and "\n" not in str(caught.value)
        assert bob.mode is ArmMode.HOLDING  # the world answers, bob holds
    assert sent == []


def test_the_live_api_client_takes_a_numpy_bool_as_a_flag(served: Served) -> None:  # noqa: F811
    """linear=np.True_ goes to the world as true: bob's tool moves 5 cm sideways in a
    straight line, arriving within 1 mm."""
    served.step_in_background()
    pose = served.world.submit(lambda: tool0(served.world)).result(timeout=30)
    goal = pose.copy()
    goal[1, 3] += 0.05
    with armfleet.connect(served.server.address) as client:
        bob = client.arm("bob")
        assert bob.move_to_pose(goal, linear=np.bool_(True)) > 0.0  # type: ignore[arg-type]
        bob.wait()
    reached = served.world.submit(lambda: tool0(served.world)).result(timeout=30)
    assert np.abs(reached[:3, 3] - goal[:3, 3]).max() < 1e-3  # [m]


def test_the_live_api_client_still_takes_a_pin_se3(served: Served) -> None:  # noqa: F811
    """A pin.SE3 goal goes to the world as its matrix and is checked there: a stretched
    rotation is refused in the world's words, bob's own tool pose is taken."""
    served.step_in_background()
    pose = served.world.submit(lambda: tool0(served.world)).result(timeout=30)
    with armfleet.connect(served.server.address) as client:
        bob = client.arm("bob")
        with pytest.raises(RemoteError, match=r"must be a rotation \(orthonormal, det \+1\)"):
            bob.move_to_pose(pin.SE3(1.5 * pose[:3, :3], pose[:3, 3].copy()))
        assert bob.move_to_pose(pin.SE3(pose[:3, :3].copy(), pose[:3, 3].copy())) >= 0.0
