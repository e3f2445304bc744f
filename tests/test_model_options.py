"""What a user says about a model file: tool link, gripper joints, home, an end effector,
and named models of one's own (armfleet/description/model_options.py, own_models.py,
end_effector.py; docs/own-robot.md)."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armfleet
from armfleet.description import ModelLibrary
from armfleet.description.home_choice import HomeSource
from armfleet.description.model_options import ModelOptions, parse_model_options
from armfleet.errors import ModelSettingError
from armfleet.remote import serve
from armfleet.spec import SpecError, load_spec
from armfleet.world.launch import launch
from tests.test_own_robot import POSE_TOLERANCE, UPSTREAM, _box_link, _write

UR5 = str(UPSTREAM["ur5"])
#: A home of the UR5 clear of itself and the floor, a gripper on it too (upper arm raised 1 rad).
UR5_HOME = [0.3, -1.0, 0.8, -0.5, 0.4, 0.2]
#: A settled arm holds its start to this [rad] (bring-up's hold tolerance is tighter).
START_RAD = 1e-3


def _gripper(path: Path, root: str = "gripper_base") -> Path:
    """A gripper description of its own: a base and two prismatic fingers, the second a
    mimic of the first, hung from a ``world`` link (as a standalone URDF is)."""
    pad = "0.02 0.01 0.04"
    return _write(
        path,
        f"""
        <robot name="gripper">
          <link name="world"/>
          <joint name="world_joint" type="fixed">
            <parent link="world"/><child link="{root}"/>
          </joint>{_box_link(root, "0.04 0.1 0.04", 0.3, "0 0 0.02")}
          {_box_link("left_pad", pad, 0.05, "0 0 0.03")}
          {_box_link("right_pad", pad, 0.05, "0 0 0.03")}
          <joint name="left_slide" type="prismatic">
            <parent link="{root}"/><child link="left_pad"/><origin xyz="0 0.02 0.04"/>
            <axis xyz="0 1 0"/><limit lower="0" upper="0.03" effort="20" velocity="0.1"/>
          </joint>
          <joint name="right_slide" type="prismatic">
            <parent link="{root}"/><child link="right_pad"/><origin xyz="0 -0.02 0.04"/>
            <axis xyz="0 -1 0"/><limit lower="0" upper="0.03" effort="20" velocity="0.1"/>
            <mimic joint="left_slide" multiplier="1" offset="0"/>
          </joint>
        </robot>
        """,
    )


def _small_arm(path: Path) -> Path:
    """Two revolute joints, a ``tool0`` and two prismatic joints named like nothing a
    gripper is inferred from (``slide_a``, ``slide_b``)."""
    limit = '<limit lower="-2" upper="2" effort="50" velocity="2"/>'
    slide = '<limit lower="0" upper="0.04" effort="20" velocity="0.1"/>'
    return _write(
        path,
        f"""
        <robot name="small">
          {_box_link("base", "0.2 0.2 0.1", 3.0, "0 0 0.05")}
          {_box_link("link1", "0.06 0.06 0.3", 1.0, "0 0 0.15")}
          {_box_link("link2", "0.06 0.06 0.3", 1.0, "0 0 0.15")}
          {_box_link("pad_a", "0.02 0.02 0.04", 0.05, "0 0 0.02")}
          {_box_link("pad_b", "0.02 0.02 0.04", 0.05, "0 0 0.02")}
          <link name="tool0"/>
          <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
            <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{limit}</joint>
          <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/>
            <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>{limit}</joint>
          <joint name="tool_joint" type="fixed"><parent link="link2"/><child link="tool0"/>
            <origin xyz="0 0 0.3"/></joint>
          <joint name="slide_a" type="prismatic"><parent link="link2"/><child link="pad_a"/>
            <origin xyz="0 0.04 0.3"/><axis xyz="0 1 0"/>{slide}</joint>
          <joint name="slide_b" type="prismatic"><parent link="link2"/><child link="pad_b"/>
            <origin xyz="0 -0.04 0.3"/><axis xyz="0 -1 0"/>{slide}</joint>
        </robot>
        """,
    )


def test_a_given_tool_link_carries_tool0_and_ends_the_arm_chain() -> None:
    with armfleet.World() as world:
        bob = world.spawn("bob", model=UR5, at=(0, 0), tool_link="wrist_2_link")
        toby = world.spawn("toby", model=UR5, at=(2, 0, 0, 180))  # the file's own tool0
        # tool0 sits on wrist_2_link, as PyBullet places that link and Pinocchio the frame.
        bob.kinematics.update(bob.body.position)
        from_bullet = bob.body.link_world_pose("bob_wrist_2_link")
        assert np.abs(bob.kinematics.world_pose("bob_tool0") - from_bullet).max() < POSE_TOLERANCE
        assert np.abs(world.tf.lookup("world", "bob_tool0") - from_bullet).max() < POSE_TOLERANCE
        # The chain ends there: wrist_3 is no arm joint; the file's own tool0 is renamed.
        assert bob.joint_names == tuple(n.replace("toby_", "bob_") for n in toby.joint_names[:5])
        assert bob.kinematics.model.existFrame("bob_file_tool0")
        toby_tool = world.tf.lookup("toby_wrist_3_link", "toby_tool0")
        bob_file_tool = world.tf.lookup("bob_wrist_3_link", "bob_file_tool0")
        assert np.abs(toby_tool - bob_file_tool).max() < 1e-9


def test_given_gripper_joints_are_the_arms_gripper_joints(tmp_path: Path) -> None:
    arm = str(_small_arm(tmp_path / "small.urdf"))
    library = ModelLibrary()
    inferred = library.expand(arm, "bob_")
    given = library.expand(arm, "bob_", options=ModelOptions(gripper_joints=("slide_a", "slide_b")))
    assert inferred.gripper_joints == ()  # nothing in their names says gripper
    assert given.gripper_joints == ("bob_slide_a", "bob_slide_b")


def test_a_given_home_is_where_the_arm_starts() -> None:
    with armfleet.World() as world:
        states: list[Any] = []
        world.bus.subscribe("/bob/joint_states", states.append)
        bob = world.spawn("bob", model=UR5, at=(0, 0), home=np.array(UR5_HOME))
        assert bob.description.home_choice is not None
        assert bob.description.home_choice.source is HomeSource.GIVEN
        assert bob.description.home == pytest.approx(UR5_HOME)
        first = np.asarray(states[0].position)[: len(UR5_HOME)]
        assert np.abs(first - UR5_HOME).max() < START_RAD
        world.run(0.2)
        assert np.abs(np.asarray(bob.positions) - UR5_HOME).max() < START_RAD


def test_an_end_effector_is_one_arm_with_the_gripper_prefixed(tmp_path: Path) -> None:
    gripper = _gripper(tmp_path / "gripper.urdf")
    with armfleet.World() as world:
        bob = world.spawn(
            "bob", model=UR5, at=(0, 0), end_effector={"file": str(gripper), "at_link": "tool0"}
        )
        world.spawn("toby", model=UR5, at=(2, 0, 0, 180))  # the arm alone
        links = bob.body.link_names
        assert {"bob_gripper_base", "bob_left_pad", "bob_right_pad"} <= set(links)
        assert all(link.startswith("bob_") for link in links) and "bob_world" not in links
        assert bob.description.gripper_joints == ("bob_left_slide", "bob_right_slide")
        # Attached at tool0, which stays where the arm alone has it.
        assert np.abs(world.tf.lookup("bob_tool0", "bob_gripper_base") - np.eye(4)).max() < 1e-9
        alone = world.tf.lookup("toby_wrist_3_link", "toby_tool0")
        assert np.abs(world.tf.lookup("bob_wrist_3_link", "bob_tool0") - alone).max() < 1e-9
        # The TF chain runs from the arm into the gripper, as PyBullet has it.
        for link in ("bob_gripper_base", "bob_left_pad", "bob_right_pad"):
            from_bullet = bob.body.link_world_pose(link)
            assert np.abs(world.tf.lookup("world", link) - from_bullet).max() < POSE_TOLERANCE
        assert world.tf.lookup("bob_wrist_3_link", "bob_left_pad").shape == (4, 4)
        assert bob.has_gripper


@pytest.fixture
def own_models(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A models folder holding ``my_arm``: the UR5 file by a relative path, a home."""
    folder = tmp_path / "models"
    robots = Path(UR5).parent
    relative = os.path.relpath(robots / "ur5_robot.urdf", folder)
    home = ", ".join(str(v) for v in UR5_HOME)
    _write(folder / "my_arm.yaml", f"file: {relative}\nhome: [{home}]\n")
    monkeypatch.setenv("ARMFLEET_MODELS_PATH", str(folder))
    return folder


def _cli(args: list[str], tmp_path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", *args],
        capture_output=True, text=True, timeout=180, check=False,
        env={**os.environ, "XDG_RUNTIME_DIR": str(tmp_path), "COLUMNS": "400"},
    )  # fmt: skip


SPAWN = ["spawn", "bob", "--at", "0,0", "--no-viewer", "--new-world", "--no-api", "--fast"]


def test_a_named_model_of_ones_own_spawns_by_name(own_models: Path, tmp_path: Path) -> None:
    with armfleet.World() as world:
        bob = world.spawn("bob", model="my_arm", at=(0, 0))
        assert bob.model == "my_arm" and len(bob.joint_names) == 6
        assert np.abs(np.asarray(bob.positions) - UR5_HOME).max() < START_RAD
    spawned = _cli([*SPAWN, "--model", "my_arm", "--duration", "0.2"], tmp_path)
    assert spawned.returncode == 0, spawned.stderr
    assert "[bob] ready" in spawned.stdout and "home: given" in spawned.stdout
    listed = _cli(["models"], tmp_path)
    assert listed.returncode == 0, listed.stderr
    row = next(line for line in listed.stdout.splitlines() if line.startswith("my_arm "))
    assert row.split()[1] == "6" and str(own_models / "my_arm.yaml") in row
    assert f"in {own_models} (ARMFLEET_MODELS_PATH)" in listed.stdout


def _clashing_gripper(tmp_path: Path) -> dict[str, str]:
    return {"file": str(_gripper(tmp_path / "g.urdf", root="base_link"))}


def _settings(tmp_path: Path, text: str) -> Path:
    folder = tmp_path / "models"
    _write(folder / "bad_arm.yaml", text)
    return folder


#: (keywords of spawn, or a settings file's text for the model "bad_arm"; what the line says)
BAD: list[Any] = [
    pytest.param({"tool_link": "nope"}, "tool_link: 'nope' is no link of the file; its links: "
                 "base_link, shoulder_link", id="unknown tool link"),
    pytest.param({"gripper_joints": ["finger"]}, "'finger' is no movable joint of the file; its "
                 "movable joints: shoulder_pan_joint", id="unknown gripper joint"),
    pytest.param({"gripper_joints": ["elbow_joint"]}, "'elbow_joint' is on the arm's chain",
                 id="gripper joint on the arm chain"),
    pytest.param({"home": [0.0, 0.0]}, "home: 2 values for 6 arm joints; give one per joint: "
                 "shoulder_pan_joint, shoulder_lift_joint", id="home of the wrong length"),
    pytest.param({"home": [0, 0, 0, 0, 0, 7.0]}, "wrist_3_joint = 7 is outside its limits",
                 id="home outside the limits"),
    pytest.param({"home": [0, -1.57, 3.1, 0, 0, 0]}, "touches itself (shoulder_link / "
                 "forearm_link)", id="home in collision"),
    pytest.param({"end_effector": {"file": "/no/such/gripper.urdf"}},
                 "end_effector.file: /no/such/gripper.urdf not found", id="end effector missing"),
    pytest.param("at_link", "end_effector.at_link: 'nowhere' is no link of the arm; its links: ",
                 id="end effector at an unknown link"),
    pytest.param("clash", "'base_link' names a link or joint of both the arm and the gripper",
                 id="link name clash"),
    pytest.param("file: UR5\ntool_link: tool0\ncolour: red\n", "bad_arm.yaml: colour: unknown "
                 "setting; valid: xacro_args, tool_link, gripper_joints, home, end_effector, file",
                 id="settings file with an unknown key"),
    pytest.param("file: [UR5\n", "bad_arm.yaml:", id="settings file not YAML"),
]  # fmt: skip


def _bad_spawn(
    given: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> tuple[str, dict[str, Any]]:
    """The model and keywords of one bad case (a settings file written if it is one)."""
    if given == "at_link":
        return UR5, {"end_effector": {"file": str(_gripper(tmp_path / "g.urdf")),
                                      "at_link": "nowhere"}}  # fmt: skip
    if given == "clash":
        return UR5, {"end_effector": _clashing_gripper(tmp_path)}
    if isinstance(given, str):
        folder = _settings(tmp_path, given.replace("UR5", UR5))
        monkeypatch.setenv("ARMFLEET_MODELS_PATH", str(folder))
        return "bad_arm", {}
    return UR5, given


@pytest.mark.parametrize(("given", "says"), BAD)
def test_a_bad_setting_is_one_line_and_nothing_is_spawned(
    given: Any, says: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    model, keywords = _bad_spawn(given, tmp_path, monkeypatch)
    with armfleet.World() as world:
        with pytest.raises(armfleet.ArmfleetError) as caught:
            world.spawn("bob", model=model, at=(0, 0), **keywords)
        message = str(caught.value)
        assert says in message and "\n" not in message, message
        assert world.arms == {}


@pytest.mark.parametrize(
    ("flags", "settings", "says"),
    [
        pytest.param(["--model", UR5, "--tool-link", "nope"], None, "'nope' is no link",
                     id="unknown tool link"),
        pytest.param(["--model", "bad_arm"], "file: UR5\ncolour: red\n", "colour: unknown setting",
                     id="settings file with an unknown key"),
        pytest.param(["--model", "bad_arm"], "file: [UR5\n", "bad_arm.yaml:",
                     id="settings file not YAML"),
    ],
)  # fmt: skip
def test_the_cli_says_a_bad_setting_in_one_line_and_exits_2(
    flags: list[str], settings: str | None, says: str, tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    if settings is not None:
        folder = _settings(tmp_path, settings.replace("UR5", UR5))
        monkeypatch.setenv("ARMFLEET_MODELS_PATH", str(folder))
    result = _cli([*SPAWN, *flags, "--duration", "0.1"], tmp_path)
    assert result.returncode == 2, result.stdout + result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and says in lines[0] and "Traceback" not in result.stderr, lines


@pytest.mark.parametrize(
    ("values", "says"),
    [
        pytest.param({"tool": "x"}, "spec: tool: unknown setting; valid: xacro_args", id="typo"),
        pytest.param({"home": [0, "a"]}, "spec: home: 'a' is not a finite number", id="home text"),
        pytest.param({"gripper_joints": ["a", "a"]}, "a given twice", id="joint twice"),
        pytest.param({"end_effector": {"at_link": "x"}}, "end_effector.file: missing",
                     id="end effector without a file"),
        pytest.param({"xacro_args": [1]}, "xacro_args: expected a mapping", id="arguments list"),
    ],
)  # fmt: skip
def test_the_parser_names_the_key(values: dict[str, Any], says: str) -> None:
    with pytest.raises(ModelSettingError) as caught:
        parse_model_options(values, "spec")
    assert says in str(caught.value) and "\n" not in str(caught.value)


def test_settings_round_trip_and_key_the_written_wrapper(tmp_path: Path) -> None:
    options = parse_model_options(
        {"xacro_args": {"hand": True}, "tool_link": "flange", "home": [0, 1],
         "end_effector": {"file": "g.urdf", "xacro_args": {"n": 2}}},
        "spec", tmp_path,
    )  # fmt: skip
    assert options.xacro_args == (("hand", "true"),)
    assert options.end_effector is not None
    assert options.end_effector.file == str(tmp_path / "g.urdf")  # relative to the settings
    assert parse_model_options(options.to_mapping(), "wire") == options
    assert hash(options) == hash(parse_model_options(options.to_mapping(), "wire"))
    library = ModelLibrary()
    assert library.path(UR5, options=ModelOptions(tool_link="wrist_2_link")) != library.path(UR5)


def test_the_live_api_takes_the_settings_and_refuses_a_bad_one(tmp_path: Path) -> None:
    """The world's process reads the files; a bad setting leaves the world as it was."""
    gripper = _gripper(tmp_path / "gripper.urdf")
    world = armfleet.World()
    server = serve(world, register=False)
    stop = threading.Event()

    def loop() -> None:
        while not stop.is_set():
            world.step()
            time.sleep(0)  # let the server's and the test's threads take the GIL

    thread = threading.Thread(target=loop)
    thread.start()
    try:
        with armfleet.connect(server.address) as client:
            bob = client.spawn(
                "bob", UR5, (0, 0), home=UR5_HOME, tool_link="wrist_3_link",
                end_effector={"file": str(gripper)}, timeout=60,
            )  # fmt: skip
            with pytest.raises(armfleet.ArmfleetError, match="'nope' is no link") as caught:
                client.spawn("toby", UR5, (2, 0), tool_link="nope", timeout=60)
            assert "\n" not in str(caught.value)
            assert list(client.arms) == ["bob"]
            assert client.call("arm", {"name": "bob"})["home"] == "home: given"
            assert np.abs(np.asarray(bob.positions) - UR5_HOME).max() < START_RAD
        described = world.arm("bob").description
        assert described.gripper_joints == ("bob_left_slide", "bob_right_slide")
        # At the tool link given (the default at_link), which tool0 is now on.
        for frame in ("bob_tool0", "bob_gripper_base"):
            pose = world.tf.lookup("bob_wrist_3_link", frame)
            assert np.abs(pose - np.eye(4)).max() < 1e-9, frame
    finally:
        stop.set()
        thread.join(timeout=30)
        server.close()
        world.close()


def test_a_spec_says_the_settings_under_model_relative_to_itself(tmp_path: Path) -> None:
    _gripper(tmp_path / "grippers" / "gripper.urdf")
    home = ", ".join(str(v) for v in UR5_HOME)
    spec = _write(
        tmp_path / "fleet.yaml",
        f"""
        arms:
          - name: bob
            model:
              file: {UR5}
              home: [{home}]
              end_effector: {{file: grippers/gripper.urdf, at_link: tool0}}
        """,
    )
    loaded = load_spec(spec)
    options = loaded.arms[0].options
    assert options.home == tuple(UR5_HOME)
    assert options.end_effector is not None
    assert options.end_effector.file == str(tmp_path / "grippers" / "gripper.urdf")
    with launch(loaded, viewer=False) as world:
        bob = world.arm("bob")
        assert bob.description.gripper_joints == ("bob_left_slide", "bob_right_slide")
        assert np.abs(np.asarray(bob.positions) - UR5_HOME).max() < START_RAD
    bad = _write(
        tmp_path / "bad.yaml",
        f"""
        arms:
          - name: bob
            model:
              file: {UR5}
              tool_link: nope
        """,
    )
    with pytest.raises(SpecError) as caught:
        load_spec(bad)
    message = str(caught.value)
    assert "bad.yaml:2" in message or "bad.yaml:3" in message, message
    assert "'nope' is no link of the file" in message and "\n" not in message
    typo = _write(
        tmp_path / "typo.yaml", f"arms:\n  - name: bob\n    model: {{file: {UR5}, tol: 1}}\n"
    )
    with pytest.raises(SpecError, match=r"typo.yaml:3.*tol"):
        load_spec(typo)
