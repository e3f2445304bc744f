"""Bad input the earlier catalogues did not list, tried as an outside auditor would (issue #14).

Three groups:

- **Refused in one line, world untouched** (``check_rejected`` of ``test_bad_input``: same
  arms, bodies, time and reference, nothing commanded, bob still holding within 1e-4 rad).
  Most are guards of classes that were already handled; ``run(on_step=5)`` was not: it
  stepped the world once, then died with ``TypeError``.
- **Reentrancy**: a bus subscriber runs in the middle of a step, while the controllers,
  the contact scan and the status loop iterate over the arms. A subscriber that removes
  an arm broke that loop (``RuntimeError: dictionary changed size during iteration``
  out of ``run``), one that steps stepped inside the step (``run(0.01)`` advanced
  13 ms), one that spawns brought an arm up inside the step, one that closes made the
  rest of the step call a disconnected PyBullet (``pybullet.error``). Now the changing
  calls are refused there with :class:`~armfleet.errors.WorldBusy` (the bus logs and
  drops that subscriber; the world goes on), and ``close`` is put off to the end of
  the step.
- **Another thread**: ``step``/``spawn`` from a second thread while ``run`` steps the
  world ran two threads in PyBullet and the controllers at once; now ``WorldBusy``
  tells it to use ``world.submit``, and the running world is untouched.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.errors import (
    ArmfleetError,
    NoGripper,
    ObjectError,
    ParameterError,
    UnknownArm,
    UnknownFrame,
    UnknownModel,
    UnknownObject,
    UnreachablePose,
    WorldBusy,
)
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.recording import RecordingError
from armfleet.recording.errors import DamagedRecording, NotARecording
from armfleet.runtime.bus import BusError, TopicError
from armfleet.spec import ArmSpec, FleetSpec, SpecError, load_spec
from tests.test_bad_input import (  # noqa: F401  (scene: a fixture)
    HOLD_CHECK_S,
    HOLD_DRIFT_RAD,
    BadInput,
    Scene,
    check_rejected,
    scene,
)
from tests.test_gripper import BOX_SIDE_M, put_box_between_fingers

#: A pose 5 m from bob's base: out of a Panda's 0.855 m reach whatever the IK does.
FAR_POSE = np.array([[1, 0, 0, 5.0], [0, 1, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 1]])


def case(action: object, error: type[ArmfleetError], *expected: str, id: str) -> object:
    return pytest.param(BadInput(action, error, lambda w, b: expected), id=id)  # type: ignore[arg-type]


def not_mcap(world: armfleet.World, bob: armfleet.Arm) -> object:
    Path("notes.mcap").write_text("hello, not a recording")
    return armfleet.open_recording("notes.mcap")


def fifo_parameters(world: armfleet.World, bob: armfleet.Arm) -> object:
    os.mkfifo("gains.yaml")  # nobody writes to it: opening it would block for ever
    return world.spawn("k", at=(0, 3), parameter_files={"position_controller": "gains.yaml"})


def fifo_mesh(world: armfleet.World, bob: armfleet.Arm) -> object:
    end = fed_fifo("rock.obj")  # fed and held open: code that reads it still ends
    try:
        return world.add_object("rock", "mesh", mesh="rock.obj", at=(2, 2, 0.5))
    finally:
        os.close(end)


def stl_over_the_limit_file(path: Path) -> None:
    """A binary STL of 200,001 triangles (0,0,0) (0.1,0,0) (0,0.1,0), 10 MB."""
    count = 200_001
    corners = np.zeros((count, 12), dtype="<f4")
    corners[:, 6] = corners[:, 10] = 0.1
    records = np.zeros(count, dtype=[("values", "<f4", 12), ("attribute", "<u2")])
    records["values"] = corners
    path.write_bytes(bytes(80) + count.to_bytes(4, "little") + records.tobytes())


def stl_over_the_limit(world: armfleet.World, bob: armfleet.Arm) -> object:
    """A binary STL of 200,001 triangles (10 MB): one over the limit, counted from its
    header. Was: accepted, PyBullet building its shape while the world waited."""
    stl_over_the_limit_file(Path("dense.stl"))
    return world.add_object("dense", "mesh", mesh="dense.stl", mass=0, at=(2, 2, 0))


def obj_polygon_over_the_limit(world: armfleet.World, bob: armfleet.Arm) -> object:
    """One OBJ face of 200,003 corners on a circle: 200,001 fan triangles in 1 face line."""
    corners = 200_003
    angles = np.linspace(0.0, 2 * math.pi, corners, endpoint=False)
    lines = [f"v {0.1 * math.cos(a):.7f} {0.1 * math.sin(a):.7f} 0" for a in angles]
    lines.append("f " + " ".join(str(i) for i in range(1, corners + 1)))
    Path("disc.obj").write_text("\n".join(lines) + "\n")
    return world.add_object("disc", "mesh", mesh="disc.obj", mass=0, at=(2, 2, 0))


def stl_over_64_mib(world: armfleet.World, bob: armfleet.Arm) -> object:
    """A 65 MiB file (sparse: nothing written), refused by its size before it is read."""
    with open("huge.stl", "wb") as stream:
        stream.truncate(65 * 2**20)
    return world.add_object("huge", "mesh", mesh="huge.stl", mass=0, at=(2, 2, 0))


def fifo_recording(world: armfleet.World, bob: armfleet.Arm) -> object:
    """A FIFO named like a recording. With nobody reading it, opening it for writing
    blocked for ever; a reader is kept open here so that, were it accepted again, the
    case fails instead of hanging."""
    os.mkfifo("pipe.mcap")
    reader = os.open("pipe.mcap", os.O_RDONLY | os.O_NONBLOCK)
    try:
        return world.record("pipe.mcap")
    finally:
        os.close(reader)


def fed_fifo(name: str) -> int:
    """A FIFO ``name`` holding a few bytes, kept open for both ends (returned) so that
    neither opening nor reading it blocks, even on code that reads it."""
    os.mkfifo(name)
    end = os.open(name, os.O_RDWR)
    os.write(end, b"not mcap")
    return end


def fifo_replay(world: armfleet.World, bob: armfleet.Arm) -> object:
    end = fed_fifo("feed.mcap")
    try:
        return armfleet.open_recording("feed.mcap")
    finally:
        os.close(end)


def huge_record(world: armfleet.World, bob: armfleet.Arm) -> object:
    """MCAP magic, then a header record claiming 2**62 bytes."""
    Path("huge.mcap").write_bytes(b"\x89MCAP0\r\n\x01" + (2**62).to_bytes(8, "little") + b"x" * 10)
    return armfleet.open_recording("huge.mcap")


REFUSED = [
    case(
        lambda w, b: w.run(0.01, on_step=5),
        ArmfleetError, "on_step takes a function", "got int",
        id="run on_step=5, not a function -> refused before any step (was TypeError after one)",
    ),
    # -- a list or dict where a name goes: was TypeError (unhashable) from a dict lookup -
    case(
        lambda w, b: w.remove(["bob"]),
        UnknownArm, "no arm named ['bob']; arms: bob",
        id="remove(['bob']), a list for an arm name -> UnknownArm listing the arms",
    ),
    case(
        lambda w, b: w.object({"name": "cube"}),
        UnknownObject, "no object named {'name': 'cube'}",
        id="object({...}), a dict for an object name -> UnknownObject",
    ),
    case(
        lambda w, b: b.move_to_pose(np.eye(4), frame=["world"]),
        UnknownFrame, "frame ['world'] not found", "frames are 'world'",
        id="move_to_pose frame=['world'], a list for a frame -> UnknownFrame listing frames",
    ),
    case(
        lambda w, b: w.spawn("z", model=["panda"], at=(3, 3)),
        UnknownModel, "model ['panda'] not found; available: panda",
        id="spawn model=['panda'], a list for a model -> UnknownModel listing the models",
    ),
    case(
        lambda w, b: w.record("run.mcap", topics=[["/bob/*"]]),
        RecordingError, "topics must be topic names or patterns (text)",
        id="record topics=[['/bob/*']], a list in the list -> RecordingError, no file",
    ),
    case(
        lambda w, b: w.move_together({}),
        ArmfleetError, "needs at least one arm",
        id="move_together {} -> asks for at least one arm",
    ),
    case(
        lambda w, b: w.move_together({"bob": b.positions, "ghost": b.positions}),
        UnknownArm, "no arm named 'ghost'", "arms: bob",
        id="move_together with an unknown arm beside bob -> UnknownArm, bob does not move either",
    ),
    case(
        lambda w, b: b.move_to_pose(FAR_POSE),
        UnreachablePose, "cannot reach the pose", "choose a pose within the arm's reach",
        id="move_to_pose 5 m away -> UnreachablePose at once, no hang, nothing moved",
    ),
    case(
        lambda w, b: w.spawn("k", at=(0, 3), parameters={"position_controller": {"kp_s2": -1.0}}),
        ParameterError, "kp_s2 = -1.0 is outside [0, 1e+06]",
        id="negative gain kp_s2=-1 -> ParameterError with its range",
    ),
    case(
        lambda w, b: w.spawn(
            "k", at=(0, 3), parameters={"position_controller": {"kd_s": math.nan}}
        ),
        ParameterError, "kd_s", "nan",
        id="gain kd_s=nan -> ParameterError",
    ),
    case(
        lambda w, b: w.spawn(
            "k", at=(0, 3), parameter_files={"position_controller": "/dev/zero"}
        ),
        ParameterError, "/dev/zero: controller parameter file is a device, not a regular file",
        "position_controller.yaml",
        id="parameter file /dev/zero -> not a regular file (was 'not found'), no endless read",
    ),
    case(
        lambda w, b: w.spawn("k", at=(0, 3), parameter_files={"position_controller": "."}),
        ParameterError, ".: controller parameter file is a folder, not a regular file",
        "give a YAML file like", "position_controller.yaml",
        id="parameter file a directory -> not a regular file (was 'not found')",
    ),
    case(
        fifo_parameters,
        ParameterError, "gains.yaml: controller parameter file is a pipe (FIFO), not a regular",
        id="parameter file a FIFO -> not a regular file, no hang",
    ),
    case(
        fifo_mesh,
        ObjectError, "rock.obj' is a pipe (FIFO), not a regular file",
        id="mesh file a FIFO -> not a regular file (was 'not found')",
    ),
    case(
        stl_over_the_limit,
        ObjectError, "dense.stl' has 200,001 triangles, over the limit of 200,000", "decimate",
        id="binary STL of 200,001 triangles -> over the 200,000 limit, decimate (was added)",
    ),
    case(
        obj_polygon_over_the_limit,
        ObjectError, "disc.obj' has 200,001 triangles, over the limit of 200,000", "decimate",
        id="OBJ polygon of 200,001 fan triangles in one face -> over the limit (was added)",
    ),
    case(
        stl_over_64_mib,
        ObjectError, "huge.stl' is 65 MiB, over the 64 MiB limit", "decimate",
        id="mesh file of 65 MiB -> over the 64 MiB limit before it is read (was read)",
    ),
    case(
        lambda w, b: w.add_object("rock", "mesh", mesh="/dev/zero", at=(2, 2, 0.5)),
        ObjectError, "unsupported mesh file", ".obj, .stl",
        id="mesh /dev/zero -> unsupported mesh file with the suffixes, nothing read",
    ),
    case(
        lambda w, b: w.add_object("cube", "box", size=(1e6, 1e6, 1e6), at=(2, 2, 0.5)),
        ObjectError, "each must be in (0, 100] m",
        id="box of 1e6 m -> ObjectError with the size range",
    ),
    case(
        lambda w, b: w.add_object("cube", "box", size=(0, 0.1, 0.1), at=(2, 2, 0.5)),
        ObjectError, "each must be in (0, 100] m",
        id="box of size 0 -> ObjectError with the size range",
    ),
    case(
        lambda w, b: w.add_object("cube", "box", size=(0.1,) * 3, mass=-1, at=(2, 2, 0.5)),
        ObjectError, "mass: -1.0 is outside [0, 10000] kg",
        id="negative mass -> ObjectError with the mass range",
    ),
    case(
        lambda w, b: w.add_object(
            "cube", "box", size=(0.1,) * 3, friction=math.nan, at=(2, 2, 0.5)
        ),
        ObjectError, "friction: nan is outside [0, 10]",
        id="friction nan -> ObjectError with the friction range",
    ),
    case(
        lambda w, b: w.add_object(
            "cube", "box", size=(0.1,) * 3, color=(2, 0, 0, 1), at=(2, 2, 0.5)
        ),
        ObjectError, "give RGBA in [0, 1]",
        id="colour component 2 -> ObjectError asking for RGBA in [0, 1]",
    ),
    case(
        lambda w, b: w.add_object("blob", "mesh", mesh=".", at=(2, 2, 0.5)),
        ObjectError, "use one of .obj, .stl",
        id="mesh path a directory -> ObjectError naming the mesh formats",
    ),
    case(
        lambda w, b: w.bus.publish("/bob/position_controller/commands", "home"),
        TopicError, "carries JointCommand, got str",
        id="text published on bob's command topic -> TopicError naming the type",
    ),
    case(
        lambda w, b: w.bus.subscribe("/bob/../x y\n", print),
        TopicError, "is malformed", "/bob/joint_states",
        id="topic with '..', a space and a newline -> TopicError with the topic rule",
    ),
    case(
        not_mcap,
        NotARecording, "not an MCAP recording",
        id="open_recording of a text file -> RecordingError, not MCAP",
    ),
    case(
        fifo_replay,
        NotARecording, "(it is a pipe (FIFO), not a regular file)",
        id="open_recording of a FIFO -> not a regular file (with no writer it hung)",
    ),
    case(
        huge_record,
        DamagedRecording, "claiming 4,611,686,018,427,387,904 bytes",
        id="recording whose record claims 2**62 bytes -> DamagedRecording, nothing allocated",
    ),
    case(
        lambda w, b: w.record("."),
        RecordingError, ".",
        id="record() to a directory -> RecordingError, nothing recorded",
    ),
    case(
        fifo_recording,
        RecordingError, "pipe.mcap: it is a pipe (FIFO), not a regular file",
        id="record() to a FIFO -> not a regular file (was accepted, or hung with no reader)",
    ),
]  # fmt: skip


@pytest.fixture(autouse=True)
def in_tmp_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Files a case writes go to the test's own folder."""
    monkeypatch.chdir(tmp_path)


@pytest.mark.parametrize("bad", REFUSED)
def test_refused_in_one_line_and_the_world_untouched(
    scene: Scene,  # noqa: F811
    bad: BadInput,
) -> None:
    objects = list(scene.world.objects)
    check_rejected(scene, bad)
    assert list(scene.world.objects) == objects


def test_gripper_commands_on_a_model_without_one(world: armfleet.World) -> None:
    """Guard: gripper close on a UR5 -> NoGripper naming a model that has one; u holds."""
    u = world.spawn("u", model="ur5")
    held = u.positions
    commands: list[Callable[[], object]] = [
        lambda: u.gripper.close(),
        lambda: u.gripper.move_to(0.01),
    ]
    for command in commands:
        with pytest.raises(NoGripper, match=r"u \(ur5\) has no gripper.*e\.g\. panda"):
            command()
    world.run(HOLD_CHECK_S)
    assert np.abs(u.positions - held).max() < HOLD_DRIFT_RAD


def test_a_second_recorder_cannot_write_into_a_file_being_recorded(world: armfleet.World) -> None:
    """Was: both accepted, records interleaved, the file read back as DamagedRecording."""
    bob = world.spawn("bob")
    first = world.record("run.mcap")
    world.run(0.1)
    with pytest.raises(RecordingError, match="another recorder is writing it") as caught:
        world.record("run.mcap")
    assert "\n" not in str(caught.value)
    bob.move_to(bob.positions + 0.1)
    world.run(0.5)
    first.stop()
    # The first recording is whole: every message it wrote reads back.
    read_back = sum(1 for _ in armfleet.open_recording("run.mcap").messages())
    assert read_back == first.message_count > 0
    # Once stopped, the file is free again.
    again = world.record("run.mcap")
    world.run(0.05)
    again.stop()
    assert sum(1 for _ in armfleet.open_recording("run.mcap").messages()) == again.message_count


def height_field(path: Path, n: int) -> None:
    """An n x n-vertex OBJ height field 0.2 m square, z = 10 mm sin(40 x) cos(40 y)."""
    xs = np.linspace(0.0, 0.2, n)
    lines = [
        f"v {x:.6f} {y:.6f} {0.01 * math.sin(40 * x) * math.cos(40 * y):.6f}"
        for x in xs
        for y in xs
    ]
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j + 1
            lines += [f"f {a} {a + 1} {a + n + 1}", f"f {a} {a + n + 1} {a + n}"]
    path.write_text("\n".join(lines) + "\n")


def test_a_dense_static_mesh_on_the_floor_does_not_kill_the_process(tmp_path: Path) -> None:
    """Was: SIGSEGV inside PyBullet's getClosestPoints (mesh vs floor) during add_object's
    clearance check, taking every arm of the world with it. A static object and the floor
    never move, so that pair is no longer asked about. Run in a child process so that a
    crash is this test's failure, not the end of the test session."""
    mesh = tmp_path / "terrain.obj"
    height_field(mesh, 230)  # 104,882 triangles: this grid crashed 6 times out of 6
    script = (
        "import armfleet\n"
        "with armfleet.World() as world:\n"
        "    bob = world.spawn('bob')\n"
        f"    terrain = world.add_object('terrain', 'mesh', mesh={str(mesh)!r}, mass=0,"
        " at=(2, 2, 0))\n"
        "    world.run(0.1)\n"
        "    print(terrain.is_static, list(world.objects), bob.position_controller.is_holding)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split()[-3:] == ["True", "['terrain']", "True"]


def test_cli_replay_of_a_fifo_is_one_line_exit_2(tmp_path: Path) -> None:
    """Was: 'armfleet replay <fifo>' blocked for ever opening it (with a writer: read it)."""
    end = fed_fifo(str(tmp_path / "feed"))
    try:
        done = subprocess.run(
            [sys.executable, "-m", "armfleet.cli.main", "replay", str(tmp_path / "feed")],
            capture_output=True,
            text=True,
            env=os.environ | {"XDG_RUNTIME_DIR": str(tmp_path)},
        )
    finally:
        os.close(end)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert "is not an MCAP recording (it is a pipe (FIFO), not a regular file)" in lines[0]


@pytest.mark.parametrize(
    "gains",
    [
        pytest.param({"kp_s2": 1e6, "kd_s": 0.0}, id="kp at its maximum, no damping -> bounded"),
        pytest.param({"kp_s2": 0.0, "kd_s": 0.0}, id="no gains at all -> bounded"),
    ],
)
def test_extreme_gains_in_range_hurt_no_neighbour(
    world: armfleet.World, gains: dict[str, float]
) -> None:
    """Guard: gains at the edges of their ranges (what a live-API client may ask for)
    leave that arm's state finite and its neighbour 1.2 m away holding, untouched."""
    bob = world.spawn("bob")
    held = bob.positions
    evil = world.spawn("evil", at=(1.2, 0), parameters={"position_controller": gains})
    evil.move_to(evil.positions + 0.3)
    world.run(1.0)
    assert np.isfinite(evil.positions).all()
    assert bob.mode is armfleet.ArmMode.HOLDING
    assert np.abs(bob.positions - held).max() < HOLD_DRIFT_RAD
    assert world.safety.stops == 0


@pytest.mark.parametrize(
    ("action", "message"),
    [
        pytest.param(
            lambda w: w.bus.subscribe("/bob/joint_states", 5),
            "subscribe: callback must be a function",
            id="subscribe a non-callable -> CallbackError now, not a dropped subscriber per step",
        ),
        pytest.param(
            lambda w: w.bus.subscribe("/bob/joint_states", print, on_error=5),
            "subscribe: on_error must be a function",
            id="subscribe with on_error=5 -> CallbackError now, not when the callback fails",
        ),
        pytest.param(
            lambda w: w.bus.subscribe_all("print"),
            "subscribe_all: callback must be a function",
            id="subscribe_all a non-callable -> CallbackError now, not a dropped tap per step",
        ),
        pytest.param(
            lambda w: w.bus.publish(["/bob/status"], None),
            "topic name ['/bob/status'] is malformed",
            id="publish to a list as topic -> TopicError, not TypeError (unhashable)",
        ),
        pytest.param(
            lambda w: w.bus.latched("///"),
            "topic name '///' is malformed",
            id="latched of a malformed topic -> TopicError, not an empty list",
        ),
        pytest.param(
            lambda w: w.bus.has_subscribers(None),
            "topic name None is malformed",
            id="has_subscribers(None) -> TopicError, not an answer about no topic",
        ),
    ],
)
def test_bus_arguments_are_checked_where_they_are_taken(
    world: armfleet.World, action: Reaction, message: str
) -> None:
    world.spawn("bob")
    topics = world.bus.topics
    with pytest.raises(BusError) as raised:
        action(world)
    assert str(raised.value).startswith(message) and "\n" not in str(raised.value)
    world.run(0.01)
    assert world.bus.failures == ()
    assert world.bus.topics == topics


def test_removing_an_arm_whose_gripper_is_closing_on_a_box(world: armfleet.World) -> None:
    """Guard: bob's fingers closing on a box (on a pedestal between them, as in
    test_gripper); bob is removed mid-close. The box stays, back at rest on its pedestal
    (within the 2 mm resting overlap of object_clearance), and the world steps on."""
    bob = world.spawn("bob")
    bob.gripper.open()
    world.run(0.8)
    put_box_between_fingers(world)
    world.run(0.2)
    box = world.object("box")
    resting = box.position
    bob.gripper.close(force=20.0)
    for _ in range(100):  # at most 1 s of simulated time
        if bob.gripper.width < BOX_SIDE_M + 2e-3:  # the pads 1 mm from the box's sides
            break
        world.run(0.01)
    assert bob.gripper.is_moving  # still closing when its arm goes
    world.remove("bob")
    world.run(0.5)
    assert list(world.arms) == [] and list(world.objects) == ["pedestal", "box"]
    assert np.abs(box.position - resting).max() < 2e-3
    assert np.abs(box.velocity).max() < 1e-2  # at rest [m/s]
    assert world.bus.failures == ()


BOB_SPEC = ArmSpec("bob", "panda", SpawnPose(0.0, 0.0))


@pytest.mark.parametrize(
    ("launch_it", "error", "says"),
    [
        pytest.param(
            lambda: armfleet.launch(FleetSpec(arms=(BOB_SPEC,)), before_spawn=5),  # type: ignore[arg-type]
            ArmfleetError, "before_spawn takes a function of the world (or None), got int",
            id="launch before_spawn=5 -> refused, not TypeError from the new world",
        ),
        pytest.param(
            lambda: armfleet.launch(FleetSpec(arms=({"name": "bob"},))),  # type: ignore[arg-type]
            SpecError, "arms[0]: must be an armfleet.spec.ArmSpec, got dict",
            id="FleetSpec arm given as a dict -> SpecError naming arms[0], not AttributeError",
        ),
        pytest.param(
            lambda: armfleet.launch(FleetSpec(arms=(BOB_SPEC,), objects=("table",))),  # type: ignore[arg-type]
            SpecError, "objects[0]: must be an armfleet.spec.ObjectSpec, got str",
            id="FleetSpec object given as a name -> SpecError naming objects[0]",
        ),
        pytest.param(
            lambda: armfleet.launch(FleetSpec(world={"dt_s": 0.001}, arms=(BOB_SPEC,))),  # type: ignore[arg-type]
            SpecError, "world: must be an armfleet.spec.WorldSpec, got dict",
            id="FleetSpec world given as a dict -> SpecError naming world",
        ),
    ],
)  # fmt: skip
def test_a_hand_built_launch_is_checked_before_any_world(
    launch_it: Callable[[], object], error: type[ArmfleetError], says: str
) -> None:
    with pytest.raises(ArmfleetError) as caught:
        launch_it()
    assert type(caught.value) is error
    assert says in str(caught.value) and "\n" not in str(caught.value)


# -- reentrancy: what a bus subscriber may not do in the middle of a step ---------------
Reaction = Callable[[armfleet.World], object]

REENTRANT = [
    pytest.param(
        lambda w: w.remove("carl"), "remove",
        id="subscriber removes an arm mid-step -> WorldBusy, carl stays (was RuntimeError)",
    ),
    pytest.param(
        lambda w: w.step(), "step",
        id="subscriber steps inside the step -> WorldBusy, time advances as run says",
    ),
    pytest.param(
        lambda w: w.spawn("dan", at=(0, -2)), "spawn",
        id="subscriber spawns mid-step -> WorldBusy, no arm brought up inside a step",
    ),
    pytest.param(
        lambda w: w.add_object("cube", "box", size=(0.05,) * 3, at=(2, 2, 0.025)), "add_object",
        id="subscriber adds an object mid-step -> WorldBusy, nothing added",
    ),
    pytest.param(
        lambda w: w.run(0.01), "run",
        id="subscriber runs the world mid-step -> WorldBusy",
    ),
]  # fmt: skip


@pytest.mark.parametrize(("react", "call"), REENTRANT)
def test_a_subscriber_cannot_change_the_world_mid_step(
    world: armfleet.World, react: Reaction, call: str
) -> None:
    bob = world.spawn("bob")
    world.spawn("carl", at=(0, 2))
    bodies = p.getNumBodies(physicsClientId=world.physics_client)
    tried: list[int] = []

    def on_status(message: object) -> None:
        if not tried:
            tried.append(1)
            react(world)

    world.bus.subscribe("/bob/status", on_status)
    start, held = world.time, bob.positions
    world.run(0.3)  # /bob/status comes every 0.1 s: the subscriber reacts once

    assert tried == [1]
    assert world.time == pytest.approx(start + 0.3, abs=world.dt / 2)  # no step inside a step
    assert list(world.arms) == ["bob", "carl"]
    assert list(world.objects) == []
    assert p.getNumBodies(physicsClientId=world.physics_client) == bodies
    failure = world.bus.failures[-1]
    assert isinstance(failure.error, WorldBusy)
    assert failure.error.call == call
    message = str(failure.error)
    assert "\n" not in message
    assert "inside a step" in message and "world.submit" in message
    assert np.abs(bob.positions - held).max() < HOLD_DRIFT_RAD
    # What the message says works: the same call handed to submit runs at the next boundary.
    if call == "remove":
        world.submit(lambda: react(world))
        world.run(HOLD_CHECK_S)
        assert list(world.arms) == ["bob"]


def test_a_subscriber_closing_the_world_ends_run_after_that_step(world: armfleet.World) -> None:
    """Was: the rest of the step called a disconnected PyBullet, ``pybullet.error`` from run."""
    world.spawn("bob")
    world.bus.subscribe("/bob/joint_states", lambda message: world.close())
    world.run(1.0)  # returns, no error
    assert world.closed
    with pytest.raises(armfleet.WorldClosed):
        world.run(0.01)


def test_on_step_may_close_the_world_and_run_returns(world: armfleet.World) -> None:
    """on_step runs between steps: it may close; run stops there instead of stepping on."""
    world.spawn("bob")
    seen: list[float] = []

    def close_at_first(w: armfleet.World) -> None:
        seen.append(w.time)
        w.close()

    world.run(1.0, on_step=close_at_first)
    assert len(seen) == 1
    assert world.closed


def test_on_step_may_spawn_between_steps(world: armfleet.World) -> None:
    """Guard: on_step is between steps, so changing the world there is allowed."""
    world.spawn("bob")

    def spawn_once(w: armfleet.World) -> None:
        if "carl" not in w.arms:
            w.spawn("carl", at=(0, 2))

    world.run(0.05, on_step=spawn_once)
    assert list(world.arms) == ["bob", "carl"]
    assert world.arm("carl").position_controller.is_holding


# -- another thread while the world runs -------------------------------------------------
OTHER_THREAD = [
    pytest.param(lambda w: w.step(), id="step from a 2nd thread during run -> WorldBusy"),
    pytest.param(
        lambda w: w.spawn("dan", at=(0, -2)),
        id="spawn from a 2nd thread during run -> WorldBusy, use submit",
    ),
    pytest.param(lambda w: w.remove("carl"), id="remove from a 2nd thread during run -> WorldBusy"),
]


@pytest.mark.parametrize("act", OTHER_THREAD)
def test_another_thread_cannot_step_or_change_a_running_world(
    world: armfleet.World, act: Reaction
) -> None:
    bob = world.spawn("bob")
    world.spawn("carl", at=(0, 2))
    errors: list[BaseException] = []

    def in_other_thread() -> None:
        try:
            act(world)
        except BaseException as exc:
            errors.append(exc)

    def at_first_step(w: armfleet.World) -> None:
        if not errors:
            thread = threading.Thread(target=in_other_thread)
            thread.start()
            thread.join()  # the other thread acts while run owns the world

    start, held = world.time, bob.positions
    world.run(0.2, on_step=at_first_step)
    assert len(errors) == 1
    assert type(errors[0]) is armfleet.WorldBusy  # exported: users catch it by name
    message = str(errors[0])
    assert "another thread" in message and "world.submit" in message and "\n" not in message
    assert world.time == pytest.approx(start + 0.2, abs=world.dt / 2)
    assert list(world.arms) == ["bob", "carl"]
    assert np.abs(bob.positions - held).max() < HOLD_DRIFT_RAD


def test_close_from_another_thread_during_run_ends_run_cleanly(world: armfleet.World) -> None:
    """The close is put off to the end of the step in progress; run returns without error."""
    world.spawn("bob")
    steps: list[float] = []

    def at_step(w: armfleet.World) -> None:
        steps.append(w.time)
        if len(steps) == 1:
            closer = threading.Thread(target=w.close)
            closer.start()
            closer.join()
            assert not w.closed  # not under the step's feet

    world.run(1.0, on_step=at_step)
    assert world.closed
    assert len(steps) == 1


def test_submit_from_another_thread_is_the_way(world: armfleet.World) -> None:
    """Guard: what WorldBusy points to works while run steps the world."""
    world.spawn("bob")
    futures: list[object] = []

    def at_step(w: armfleet.World) -> None:
        if not futures:
            thread = threading.Thread(
                target=lambda: futures.append(w.submit(lambda: w.spawn("dan", at=(0, -2))))
            )
            thread.start()
            thread.join()

    world.run(0.05, on_step=at_step)
    assert list(world.arms) == ["bob", "dan"]


def controller_file_spec(tmp_path: Path, make: Callable[[Path], str]) -> Path:
    """A spec in ``tmp_path`` whose position_controller file is what ``make`` names."""
    name = make(tmp_path)
    spec = tmp_path / "cell.yaml"
    spec.write_text(
        "arms:\n  - name: bob\n    model: panda\n    controllers:\n"
        f"      position_controller: {{file: {name}}}\n"
    )
    return spec


def fifo_named(tmp_path: Path) -> str:
    os.mkfifo(tmp_path / "gains.yaml")  # nobody writes to it: opening it would block
    return "gains.yaml"


def folder_named(tmp_path: Path) -> str:
    (tmp_path / "gains").mkdir()
    return "gains"


@pytest.mark.parametrize(
    ("make", "problem"),
    [
        pytest.param(
            folder_named, "'gains' is a folder, not a regular file",
            id="spec's controller file a folder -> not a regular file (was 'not found next to')",
        ),
        pytest.param(
            lambda tmp: "/dev/zero", "'/dev/zero' is a device, not a regular file",
            id="spec's controller file /dev/zero -> not a regular file (was 'not found')",
        ),
        pytest.param(
            fifo_named, "'gains.yaml' is a pipe (FIFO), not a regular file",
            id="spec's controller file a FIFO -> not a regular file (was 'not found'), no hang",
        ),
    ],
)  # fmt: skip
def test_a_spec_naming_a_controller_file_that_is_no_regular_file(
    tmp_path: Path, make: Callable[[Path], str], problem: str
) -> None:
    """The Python loader and ``launch --check`` both say what the file is, on its line."""
    spec = controller_file_spec(tmp_path, make)
    with pytest.raises(SpecError) as raised:
        load_spec(spec)
    expected = f"{spec}:5: arms[0].controllers.position_controller.file: controller file {problem}"
    assert str(raised.value) == expected
    done = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "launch", str(spec), "--check"],
        capture_output=True,
        text=True,
        env=os.environ | {"XDG_RUNTIME_DIR": str(tmp_path)},
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert problem in line


def test_cli_launch_of_a_fifo_is_one_line_exit_2(tmp_path: Path) -> None:
    """Was: 'armfleet launch <fifo>' said 'no such spec file' of a file that is there."""
    end = fed_fifo(str(tmp_path / "cell.yaml"))  # fed and held open: no hang on old code
    try:
        done = subprocess.run(
            [sys.executable, "-m", "armfleet.cli.main", "launch", str(tmp_path / "cell.yaml")],
            capture_output=True,
            text=True,
            env=os.environ | {"XDG_RUNTIME_DIR": str(tmp_path)},
        )
    finally:
        os.close(end)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert "cell.yaml: is a pipe (FIFO), not a regular file; give a spec file (.yaml)" in line


def test_cli_launch_check_of_a_spec_with_a_mesh_over_the_limit(tmp_path: Path) -> None:
    """The mesh limit holds on the launch-spec path too: ``launch --check`` refuses in one
    line, on the mesh's line, before any world (was: passed the check)."""
    stl_over_the_limit_file(tmp_path / "dense.stl")
    spec = tmp_path / "cell.yaml"
    spec.write_text(
        "objects:\n  - name: dense\n    shape: mesh\n    mesh: dense.stl\n    mass_kg: 0\n"
    )
    done = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "launch", str(spec), "--check"],
        capture_output=True,
        text=True,
        env=os.environ | {"XDG_RUNTIME_DIR": str(tmp_path)},
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert f"{spec}:4: objects[0].mesh: mesh file " in line
    assert "has 200,001 triangles, over the limit of 200,000" in line and "decimate" in line
