"""A robot of one's own on the other surfaces, as a Panda works there: the live API (a world
in another process, and the CLI joining it from another folder), Foxglove, the Reach
environment and sweeps.

The files are vendors' (example-robot-data's UR5 and SO-100), given by path with no
wrapper. What is expected is read off the files themselves (``xml.etree``) and computed
with Pinocchio from the vendor's file, not asked of armfleet.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
import textwrap
import threading
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import armfleet
from armfleet.services.errors import RemoteError
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env
from tests.test_foxglove import FoxgloveClient
from tests.test_own_robot import ROBOTS, UPSTREAM
from tests.test_own_robot_front_ends import movable_joints

#: The prefix of example-robot-data's ``package://`` URIs, and where it is on disk.
VENDOR_PACKAGE = "package://example-robot-data/"
#: Tool poses agree with the vendor file's forward kinematics to this [m, rotation
#: entries] (the observation is float32: ~1e-7 relative, on values up to ~1 m).
POSE_TOLERANCE = 1e-5
#: An arm joint ends this close to where the actions sent it [rad].
TRACKING_RAD = 1e-3


def robot_name(urdf: Path) -> str:
    return ET.parse(urdf).getroot().get("name", "")


def vendor_meshes(urdf: Path) -> list[Path]:
    """Every mesh the file names (visual and collision), as files on disk."""
    names = [mesh.get("filename", "") for mesh in ET.parse(urdf).getroot().iter("mesh")]
    assert all(name.startswith(VENDOR_PACKAGE) for name in names), names
    return [ROBOTS.parent / name.removeprefix(VENDOR_PACKAGE) for name in names]


# -- the live API ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    """A world with bob (a Panda), run by ``armfleet spawn`` in another process."""
    runtime = tmp_path_factory.mktemp("runtime")
    with WorldProcess(runtime, "bob", "--at", "0,0", "--no-viewer") as world:
        yield world


def test_the_live_api_brings_up_vendor_files_from_the_client_and_from_another_folder(
    running: WorldProcess, tmp_path: Path
) -> None:
    with armfleet.connect(running.address) as client:
        carl = client.spawn("carl", model=str(UPSTREAM["ur5"]), at=(2.0, 0.0))
        assert carl.joint_names == tuple(f"carl_{j}" for j in movable_joints(UPSTREAM["ur5"]))
        assert carl.model == str(UPSTREAM["ur5"])
        # The CLI joins the running world from a folder of its own, the file given relative
        # to it: the world's process (in /work/main's folder) reads the same file.
        folder = tmp_path / "elsewhere"
        (folder / "arms").mkdir(parents=True)
        copied = Path(shutil.copy(UPSTREAM["so100"], folder / "arms" / "so100.urdf"))
        assert Path.cwd() != folder
        joined = subprocess.run(
            [*ARMFLEET, "spawn", "dora", "--at", "4,0", "--model", "./arms/so100.urdf"],
            cwd=folder,
            capture_output=True,
            text=True,
            timeout=120,
            env=runtime_env(running.runtime_dir),
        )
        assert joined.returncode == 0, joined.stderr
        assert "dora ready in the world" in joined.stdout
        dora = client.arm("dora")
        assert dora.model == str(copied)
        movable = {f"dora_{joint}" for joint in movable_joints(copied)}
        assert set(dora.joint_names) < movable and dora.has_gripper  # the jaw: its gripper
        assert list(client.arms) == ["bob", "carl", "dora"]
        assert np.allclose(client.arm("carl").pose.x, 2.0) and dora.pose.x == 4.0
    # ``armfleet arms`` shows each model file by the name the user gave it (the whole path
    # is the arm's ``model``, above), not a wrapper's name.
    listed = cli(running.runtime_dir, "arms")
    assert listed.returncode == 0, listed.stderr
    rows = {line.split()[0]: line.split()[1] for line in listed.stdout.splitlines()[1:4]}
    assert rows == {"bob": "panda", "carl": UPSTREAM["ur5"].name, "dora": copied.name}


def _hidden_from_the_world(folder: Path, running: WorldProcess) -> subprocess.CompletedProcess[str]:
    """``armfleet spawn`` of a UR5 file that only the client's mount namespace holds: a
    tmpfs mounted over ``folder`` in a namespace of its own (the world's ``folder`` stays
    empty). The CLI reads and checks the file on its side, the world's process cannot."""
    script = (
        'src="$1" python="$2"; shift 2; '
        'mount -t tmpfs tmpfs "$0" && cp "$src" "$0/" && exec "$python" -m armfleet.cli.main "$@"'
    )
    command = [
        *("unshare", "--mount", "--propagation", "private", "sh", "-c", script),
        *(str(folder), str(UPSTREAM["ur5"]), sys.executable),
        *("spawn", "eve", "--at", "6,0", "--model", str(folder / "ur5_robot.urdf")),
    ]
    return subprocess.run(
        command,
        capture_output=True,
        text=True,
        timeout=120,
        env=runtime_env(running.runtime_dir),
    )


def _can_unshare() -> bool:
    tool = shutil.which("unshare")
    return (
        os.geteuid() == 0
        and tool is not None
        and subprocess.run([tool, "-m", "true"]).returncode == 0
    )


@pytest.mark.parametrize(
    "how",
    [
        pytest.param("nowhere", id="a path that is nowhere"),
        pytest.param(
            "hidden",
            id="a file only the client's mount namespace holds",
            marks=pytest.mark.skipif(not _can_unshare(), reason="needs root and unshare -m"),
        ),
        pytest.param(
            "mode 000",
            id="a file the world's user may not read",
            marks=pytest.mark.skipif(os.geteuid() == 0, reason="root reads any file"),
        ),
    ],
)
def test_a_file_the_world_cannot_read_is_one_line_and_leaves_the_world_as_it_was(
    running: WorldProcess, tmp_path: Path, how: str
) -> None:
    with armfleet.connect(running.address) as client:
        before = {name: arm.positions for name, arm in client.arms.items()}
        if how == "hidden":
            folder = tmp_path / "client_only"
            folder.mkdir()
            refused = _hidden_from_the_world(folder, running)
            assert refused.returncode == 2, (refused.stdout, refused.stderr)
            lines = refused.stderr.splitlines()
            assert len(lines) == 1 and "Traceback" not in refused.stderr, refused.stderr
            line = lines[0]
            assert not (folder / "ur5_robot.urdf").exists()  # here, as in the world
        else:
            path = tmp_path / ("nowhere" if how == "nowhere" else "") / "arm.urdf"
            if how == "mode 000":
                path.write_text(UPSTREAM["ur5"].read_text())
                path.chmod(0)
            with pytest.raises(RemoteError) as raised:
                client.spawn("eve", model=str(path), at=(6.0, 0.0))
            line = str(raised.value)
            assert "\n" not in line
        reason = "not found" if how != "mode 000" else "permission denied"
        assert f"as the process that owns the world (process {running.pid} on " in line
        assert f"sees it: {reason}; that process reads model files, not the client" in line
        assert "ur5_robot.urdf" in line or "arm.urdf" in line
        after = {name: arm.positions for name, arm in client.arms.items()}
        assert list(after) == list(before)  # no eve, nobody removed
        assert all(np.abs(after[name] - before[name]).max() < TRACKING_RAD for name in before)


# -- Foxglove ----------------------------------------------------------------------------
def _step(world: armfleet.World, stop: threading.Event) -> None:
    while not stop.is_set() and not world.closed:
        world.run(0.02, realtime=True)


def test_foxglove_serves_the_vendor_files_robot_description_and_every_mesh() -> None:
    arms = {"carl": UPSTREAM["ur5"], "dora": UPSTREAM["so100"]}
    world = armfleet.World()
    stop = threading.Event()
    stepper = threading.Thread(target=_step, args=(world, stop), daemon=True)
    try:
        world.spawn("carl", model=str(arms["carl"]), at=(0.0, 0.0))
        world.spawn("dora", model=str(arms["dora"]), at=(2.0, 0.0))
        server = world.serve_foxglove(0)
        stepper.start()
        client = FoxgloveClient.open(server.url)
        try:
            topics = [f"/{name}/robot_description" for name in arms]
            client.subscribe(*topics)
            client.wait_for(lambda: all(client.messages[topic] for topic in topics))
            for name, path in arms.items():
                urdf = client.messages[f"/{name}/robot_description"][0].json["data"]
                robot = ET.fromstring(urdf)
                assert robot.get("name") == robot_name(path)  # not a generated file's name
                links = {link.get("name") for link in robot.iter("link")}
                vendor = ET.parse(path).getroot()
                own = {link.get("name") for link in vendor.iter("link")} - {"world"}
                assert {f"{name}_{link}" for link in own} <= links  # world: armfleet's
                uris = [mesh.get("filename", "") for mesh in robot.iter("mesh")]
                expected = vendor_meshes(path)
                assert len(uris) == len(expected) and all(u.startswith("package://") for u in uris)
                served = []
                for uri in uris:
                    ok, data = client.fetch(uri)
                    assert ok, (uri, data)
                    served.append(data)
                assert served == [mesh.read_bytes() for mesh in expected]  # in the file's order
                ok, text = client.fetch(f"package://armfleet/robots/{name}.urdf")
                assert ok and ET.fromstring(text).get("name") == robot_name(path)
        finally:
            client.close()
    finally:
        stop.set()
        if stepper.is_alive():
            stepper.join(timeout=10)
        world.close()


# -- the environments --------------------------------------------------------------------
def _vendor_tool0(urdf: Path, positions: np.ndarray, base: np.ndarray) -> np.ndarray:
    """tool0's world pose by Pinocchio from the vendor's file, its base at ``base``."""
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    pin.framesForwardKinematics(model, data, positions)
    pose: np.ndarray = base @ data.oMf[model.getFrameId("tool0")].homogeneous
    return pose


def _pose_matrix(vector: np.ndarray) -> np.ndarray:
    """x, y, z, qx, qy, qz, qw as a 4x4 matrix."""
    matrix = np.eye(4)
    x, y, z, qx, qy, qz, qw = (float(v) for v in vector)
    matrix[:3, :3] = pin.Quaternion(qw, qx, qy, qz).normalized().matrix()
    matrix[:3, 3] = (x, y, z)
    return matrix


def test_a_reach_episode_with_a_ur5_file_passes_gymnasiums_checker_and_follows_its_actions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    gym = pytest.importorskip("gymnasium")
    from gymnasium.utils.env_checker import check_env

    import armfleet.envs

    # Given relative to the working folder, as a user would; taken absolute at once.
    shutil.copy(UPSTREAM["ur5"], tmp_path / "ur5.urdf")
    monkeypatch.chdir(tmp_path)
    env = gym.make("armfleet/Reach-v0", arm_count=1, model="./ur5.urdf")
    try:
        reach = env.unwrapped
        assert isinstance(reach, armfleet.envs.ReachEnv)
        assert isinstance(reach.task, armfleet.envs.ReachTask)
        assert reach.task.model == str(tmp_path / "ur5.urdf")  # every episode's file
        check_env(reach, skip_render_check=True)
        observation, info = env.reset(seed=7)
        arm = reach.world.arm("arm0")
        assert arm.model == str(tmp_path / "ur5.urdf")
        vendor_joints = movable_joints(UPSTREAM["ur5"])
        assert arm.joint_names == tuple(f"arm0_{joint}" for joint in vendor_joints)
        start = observation["arm0"]["joint_positions"].astype(float)
        # The first joint turns 0.01 rad a step for 100 steps, then the arm is held.
        delta = np.zeros(len(vendor_joints), dtype=np.float32)
        delta[0] = 0.01
        still = np.zeros_like(delta)
        base = armfleet.SpawnPose(0.0, 0.0, 0.0, 90.0).matrix()  # Reach's row faces +y
        steps, truncated, terminated = 0, False, False
        while not (terminated or truncated):
            action = {"arm0": {"joint_deltas": delta if steps < 100 else still}}
            observation, reward, terminated, truncated, info = env.step(action)
            steps += 1
            seen = observation["arm0"]
            tool = _pose_matrix(seen["tool_pose"])
            joints = seen["joint_positions"].astype(float)
            expected = _vendor_tool0(UPSTREAM["ur5"], joints, base)
            assert np.abs(tool - expected).max() < POSE_TOLERANCE, steps
            distance = np.linalg.norm(seen["target_pose"][:3] - seen["tool_pose"][:3])
            assert math.isclose(reward, -distance, abs_tol=1e-6)
        assert info["stopped"] == [] and info["refused"] == {}
        assert truncated and steps == 200  # Reach's episode: 200 steps
        end = observation["arm0"]["joint_positions"].astype(float)
        moved = start.copy()
        moved[0] += 100 * 0.01
        assert np.abs(end - moved).max() < TRACKING_RAD
    finally:
        env.close()


def test_reach_with_an_unknown_model_is_refused_in_one_line() -> None:
    gym = pytest.importorskip("gymnasium")
    import armfleet.envs  # registers the ids

    with pytest.raises(armfleet.ArmfleetError) as raised:
        gym.make("armfleet/Reach-v0", arm_count=1, model="ur55")
    assert "ur55" in str(raised.value) and "panda" in str(raised.value)
    assert "\n" not in str(raised.value)


# -- sweeps ------------------------------------------------------------------------------
TASK = '''
import numpy as np


def task(world, rng, *, move_rad: float = 0.15):
    """Move every joint of carl ``move_rad`` towards the middle of its range; settle."""
    arm = world.arm("carl")
    lower, upper = arm.joint_limits
    start = np.asarray(arm.positions)
    target = start + move_rad * np.sign((lower + upper) / 2 - start + 1e-9)
    world.run(arm.move_to(target) + 0.3)
    base = world.tf.lookup("world", "carl_base_link")
    return {
        "model": arm.model,
        "joints": len(arm.joint_names),
        "tracking_error_rad": float(np.abs(np.asarray(arm.positions) - target).max()),
        "yaw_deg": float(np.degrees(np.arctan2(base[1, 0], base[0, 0]))),
        "stops": world.safety.stops,
    }
'''


def test_a_sweep_of_a_spec_whose_arm_is_a_model_file_runs_without_ray(tmp_path: Path) -> None:
    from armfleet.sweeps import load_sweep
    from armfleet.sweeps.batch import run_batch

    (tmp_path / "robots").mkdir()
    shutil.copy(UPSTREAM["ur5"], tmp_path / "robots" / "ur5.urdf")
    (tmp_path / "wave.py").write_text(TASK)
    spec = tmp_path / "ur5_wave.yaml"
    spec.write_text(
        textwrap.dedent(
            """
            world: {dt_s: 0.001, viewer: false}
            arms:
              - name: carl
                model: {file: robots/ur5.urdf}     # relative to this spec
                at_m: [0, 0]
            sweep:
              task: wave.py
              runs: 2
              randomize:
                arms.carl.yaw_deg: {uniform: [-90, 90]}
            """
        )
    )
    definition = load_sweep(spec)
    rows = run_batch(definition, [0, 1])
    assert [row["seed"] for row in rows] == [0, 1]
    assert all(row["ok"] for row in rows), [row["error"] for row in rows]
    joints = len(movable_joints(UPSTREAM["ur5"]))
    for row in rows:
        metrics = row["metrics"]
        assert metrics["model"] == str(tmp_path / "robots" / "ur5.urdf")
        assert metrics["joints"] == joints and metrics["stops"] == 0
        assert metrics["tracking_error_rad"] < TRACKING_RAD
        drawn = row["arms.carl.yaw_deg"]
        assert -90.0 <= drawn < 90.0 and abs(metrics["yaw_deg"] - drawn) < 1e-6
    assert rows[0]["arms.carl.yaw_deg"] != rows[1]["arms.carl.yaw_deg"]


def test_the_reach_scenario_takes_a_model_file() -> None:
    from armfleet.scenarios.reach import reach

    with armfleet.World() as world:
        metrics = reach(world, np.random.default_rng(3), arm_count=1, model=str(UPSTREAM["ur5"]))
        arm = world.arm("arm0")
        assert arm.joint_names == tuple(f"arm0_{j}" for j in movable_joints(UPSTREAM["ur5"]))
        assert arm.model == str(UPSTREAM["ur5"])
        tool = world.tf.lookup("world", arm.description.tool0)
    assert metrics["arms"] == 1 and metrics["targets"] == 1
    # A target missed has its cause among the metrics (a stop, IK, or a self-touching goal
    # refused), else it was reached.
    figures = {name: float(value) for name, value in metrics.items()}
    missed = figures["reached_fraction"] < 1.0
    causes = figures["stops"] + figures["ik_failures"] + figures["self_contact_refusals"]
    assert not missed or causes >= 1, metrics
    assert missed or figures["max_position_error_m"] < 0.005
    assert np.isfinite(tool).all()
