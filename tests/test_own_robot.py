"""A robot of one's own, by path: descriptions this project did not write, prefixed and
placed like bob and toby (armfleet/description/file_model.py, docs/own-robot.md)."""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import textwrap
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.description import ModelLibrary
from armfleet.errors import DescriptionError, PackageNotFound
from tests.test_check_model import collada_cube

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"
#: Vendors' fixed-base arms as example-robot-data ships them, loaded with no wrapper.
UPSTREAM = {
    "panda": ROBOTS / "panda_description/urdf/panda.urdf",
    "ur5": ROBOTS / "ur_description/urdf/ur5_robot.urdf",
    "ur3_gripper": ROBOTS / "ur_description/urdf/ur3_gripper.urdf",
    "so100": ROBOTS / "so_arm_description/urdf/so100.urdf",
    "so101": ROBOTS / "so_arm_description/urdf/so101.urdf",
    "xarm7": ROBOTS / "xarm_description/urdf/xarm7.urdf",
}
#: Frames computed three ways agree to this [m, rotation entries].
POSE_TOLERANCE = 1e-6
#: Every arm joint tracks a 0.15 rad move to this once it has settled [rad].
TRACKING_RAD = 1e-3
MOVE_RAD = 0.15


def _two_copies(model: str) -> armfleet.World:
    world = armfleet.World()
    world.spawn("bob", model=model, at=(0.0, 0.0))
    world.spawn("toby", model=model, at=(2.0, 0.0, 0.0, 180.0))  # out of each other's reach
    return world


@pytest.mark.parametrize("name", sorted(UPSTREAM))
def test_a_vendor_file_by_path_comes_up_twice_prefixed_and_tracks(name: str) -> None:
    with _two_copies(str(UPSTREAM[name])) as world:
        bob, toby = world.arm("bob"), world.arm("toby")
        for arm in (bob, toby):
            links = arm.body.link_names
            assert links and all(link.startswith(f"{arm.name}_") for link in links)
            assert all(joint.startswith(f"{arm.name}_") for joint in arm.joint_names)
            assert arm.kinematics.model.existFrame(f"{arm.name}_tool0")
        # The spawn transform is the TF's world -> <name>_base_link.
        expected = armfleet.SpawnPose(2.0, 0.0, 0.0, 180.0).matrix()
        assert np.abs(world.tf.lookup("world", "toby_base_link") - expected).max() < 1e-9
        # Every arm joint 0.15 rad away from home (within its limits), then back to rest.
        _, upper = bob.joint_limits
        home = np.asarray(bob.positions)
        target = np.where(home + MOVE_RAD <= upper, home + MOVE_RAD, home - MOVE_RAD)
        bob.move_to(target)
        world.run(0.2)
        assert bob.is_moving
        bob.kinematics.update(bob.body.position)
        for link in bob.body.link_names:  # mid-motion, three ways
            from_bullet = bob.body.link_world_pose(link)
            from_pinocchio = bob.kinematics.world_pose(link)
            from_tf = world.tf.lookup("world", link)
            assert np.abs(from_bullet - from_pinocchio).max() < POSE_TOLERANCE, link
            assert np.abs(from_tf - from_pinocchio).max() < POSE_TOLERANCE, link
        while bob.is_moving:
            world.run(0.1)
        world.run(0.2)
        assert np.abs(bob.positions - target).max() < TRACKING_RAD
        assert bob.mode is armfleet.ArmMode.HOLDING and toby.mode is armfleet.ArmMode.HOLDING


def test_a_package_uri_names_the_same_file_as_its_path() -> None:
    uri = "package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
    with armfleet.World() as world:
        by_uri = world.spawn("bob", model=uri, at=(0, 0))
        by_path = world.spawn("toby", model=str(UPSTREAM["ur5"]), at=(2.0, 0))
        assert by_uri.joint_names == tuple(
            name.replace("toby_", "bob_") for name in by_path.joint_names
        )
        assert by_uri.description.home == by_path.description.home


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip())
    return path


def _box_link(name: str, size: str, mass: float, xyz: str = "0 0 0") -> str:
    inertia = mass * 0.01
    return f"""
      <link name="{name}">
        <visual><origin xyz="{xyz}"/><geometry><box size="{size}"/></geometry></visual>
        <collision><origin xyz="{xyz}"/><geometry><box size="{size}"/></geometry></collision>
        <inertial><origin xyz="{xyz}"/><mass value="{mass}"/>
          <inertia ixx="{inertia}" ixy="0" ixz="0" iyy="{inertia}" iyz="0" izz="{inertia}"/>
        </inertial>
      </link>"""


@pytest.fixture
def workspace(tmp_path: Path) -> Path:
    """Two ROS packages as a vendor ships them: ``my_arm_description`` (the arm's xacro,
    its own ``tf_prefix`` argument, a YAML of joint limits read with ``xacro.load_yaml``, a
    ``<ros2_control>`` and a ``<gazebo>`` block, no tool0) including a macro of
    ``my_parts`` through ``$(find my_parts)``."""
    src = tmp_path / "ws" / "src"
    _write(src / "my_parts" / "package.xml", "<package><name>my_parts</name></package>")
    links = "".join(
        _box_link(f"${{p}}link{i}", "0.06 0.06 0.3", 1.0, "0 0 0.15") for i in (1, 2, 3)
    )
    _write(
        src / "my_parts" / "urdf" / "parts.xacro",
        f"""
        <robot xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:macro name="three_links" params="p">{links}
          </xacro:macro>
        </robot>
        """,
    )
    package = src / "my_arm_description"
    _write(package / "package.xml", "<package><name>my_arm_description</name></package>")
    _write(package / "config" / "limits.yaml", "effort: 50.0\nvelocity: 2.0\nrange: 2.5\n")
    base = _box_link("${tf_prefix}base", "0.2 0.2 0.1", 3.0, "0 0 0.05")
    _write(
        package / "urdf" / "my_arm.urdf.xacro",
        f"""
        <?xml version="1.0"?>
        <robot name="my_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:arg name="tf_prefix" default=""/>
          <xacro:arg name="reach" default="long"/>
          <xacro:property name="tf_prefix" value="$(arg tf_prefix)"/>
          <xacro:property name="reach" value="$(arg reach)"/>
          <xacro:property name="limits"
              value="${{xacro.load_yaml('$(find my_arm_description)/config/limits.yaml')}}"/>
          <xacro:include filename="$(find my_parts)/urdf/parts.xacro"/>
          <link name="world"/>
          <joint name="${{tf_prefix}}world_joint" type="fixed">
            <parent link="world"/><child link="${{tf_prefix}}base"/>
          </joint>{base}
          <xacro:three_links p="${{tf_prefix}}"/>
          <xacro:macro name="joint" params="name parent child z axis">
            <joint name="${{tf_prefix}}${{name}}" type="revolute">
              <parent link="${{tf_prefix}}${{parent}}"/><child link="${{tf_prefix}}${{child}}"/>
              <origin xyz="0 0 ${{z}}"/><axis xyz="${{axis}}"/>
              <limit lower="${{-limits['range']}}" upper="${{limits['range']}}"
                     effort="${{limits['effort']}}" velocity="${{limits['velocity']}}"/>
            </joint>
          </xacro:macro>
          <xacro:joint name="joint1" parent="base" child="link1" z="0.1" axis="0 0 1"/>
          <xacro:joint name="joint2" parent="link1" child="link2" z="0.3" axis="0 1 0"/>
          <xacro:joint name="joint3" parent="link2" child="link3" axis="0 1 0"
                       z="${{0.3 if reach == 'long' else 0.15}}"/>
          <ros2_control name="my_arm" type="system">
            <hardware><plugin>mock_components/GenericSystem</plugin></hardware>
            <joint name="${{tf_prefix}}joint1"><command_interface name="position"/></joint>
          </ros2_control>
          <gazebo reference="${{tf_prefix}}link1"><material>Gazebo/Orange</material></gazebo>
        </robot>
        """,
    )
    return src


def test_a_vendor_xacro_with_find_across_packages_load_yaml_and_arguments(
    workspace: Path,
) -> None:
    package = workspace / "my_arm_description"
    model = str(package / "urdf" / "my_arm.urdf.xacro")
    models = ModelLibrary(package_paths=[workspace])
    with armfleet.World(models=models) as world:
        # The file's own prefix argument may be used or not: the names are the same.
        bob = world.spawn("bob", model=model, at=(0, 0), xacro_args={"tf_prefix": "vendor_"})
        toby = world.spawn("toby", model=model, at=(1, 0), xacro_args={"reach": "short"})
        assert bob.joint_names == ("bob_vendor_joint1", "bob_vendor_joint2", "bob_vendor_joint3")
        assert toby.joint_names == ("toby_joint1", "toby_joint2", "toby_joint3")
        # The argument took effect: toby's third link is half as far out.
        assert world.tf.lookup("bob_vendor_link2", "bob_vendor_link3")[2, 3] == pytest.approx(0.3)
        assert world.tf.lookup("toby_link2", "toby_link3")[2, 3] == pytest.approx(0.15)
        lower, upper = bob.joint_limits
        assert np.allclose(lower, -2.5) and np.allclose(upper, 2.5)  # from the YAML
        # No tool0 in the file: the end of the longest chain (link3) carries it.
        tool = world.tf.lookup("bob_vendor_link3", "bob_tool0")
        assert np.abs(tool - np.eye(4)).max() < 1e-12
        assert "ros2_control" not in bob.description.urdf and "gazebo" not in bob.description.urdf
        target = np.asarray(bob.positions) + 0.3
        bob.move_to(target)
        while bob.is_moving:
            world.run(0.1)
        world.run(0.2)
        assert np.abs(bob.positions - target).max() < TRACKING_RAD


def test_without_the_package_path_the_find_names_the_package_and_the_places(
    workspace: Path,
) -> None:
    model = str(workspace / "my_arm_description" / "urdf" / "my_arm.urdf.xacro")
    with armfleet.World() as world, pytest.raises(DescriptionError) as caught:
        world.spawn("bob", model=model)
    assert "my_arm_description" in str(caught.value) or "my_parts" in str(caught.value)
    assert world.arms == {}


BAD_URDF = "<robot name='x'>{}</robot>"


@pytest.mark.parametrize(
    ("file_name", "content", "says"),
    [
        pytest.param("arm.txt", "hello", "neither .urdf nor", id="not a description file"),
        pytest.param("arm.urdf", "<robot", "not valid XML", id="not XML"),
        pytest.param("arm.urdf", "<sdf/>", "root is <robot>", id="not URDF"),
        pytest.param(
            "arm.urdf",
            BAD_URDF.format(
                _box_link("a", "0.1 0.1 0.1", 1) + _box_link("b", "0.1 0.1 0.1", 1)
                + '<joint name="j" type="floating"><parent link="a"/><child link="b"/></joint>'
            ),
            "joint 'j' is floating",
            id="a floating joint",
        ),
        pytest.param(
            "arm.urdf",
            BAD_URDF.format(_box_link("a", "0.1 0.1 0.1", 1) + _box_link("b", "0.1 0.1 0.1", 1)),
            "2 root links",
            id="two roots",
        ),
        pytest.param(
            "arm.urdf",
            BAD_URDF.format(
                _box_link("a", "0.1 0.1 0.1", 1) + _box_link("b", "0.1 0.1 0.1", 1)
                + '<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>'
            ),
            "no movable joint",
            id="nothing moves",
        ),
        pytest.param(
            "arm.urdf.xacro",
            '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:nothing/></robot>',
            "xacro failed",
            id="a xacro error",
        ),
        pytest.param(
            "arm.urdf.xacro",
            '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
            '<xacro:include filename="$(find no_such_package)/x.xacro"/></robot>',
            "no_such_package",
            id="an unresolvable $(find)",
        ),
        pytest.param(
            "arm.urdf",
            "<robot>" + " " * 10_000_000 + "</robot>",
            "too large for a robot description",
            id="a file over 10 MB",
        ),
    ],
)  # fmt: skip
def test_a_bad_file_is_one_line_and_the_world_is_untouched(
    tmp_path: Path, file_name: str, content: str, says: str
) -> None:
    path = _write(tmp_path / file_name, content)
    with armfleet.World() as world:
        world.spawn("ned", at=(2, 2))
        with pytest.raises(armfleet.ArmfleetError) as caught:
            world.spawn("bob", model=str(path))
        message = str(caught.value)
        assert says in message and "\n" not in message, message
        assert list(world.arms) == ["ned"]


def test_a_missing_file_an_unknown_argument_and_a_binary_file_are_refused(
    tmp_path: Path,
) -> None:
    xacro_file = _write(
        tmp_path / "arm.urdf.xacro",
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:arg name="size"'
        ' default="1"/></robot>',
    )
    binary = tmp_path / "arm.urdf"
    binary.write_bytes(b"\xff\xfe<robot/>")
    with armfleet.World() as world:
        with pytest.raises(DescriptionError, match="not found"):
            world.spawn("bob", model=str(tmp_path / "nothing.urdf"))
        with pytest.raises(DescriptionError, match="unknown xacro argument ur_type; its "):
            world.spawn("bob", model=str(xacro_file), xacro_args={"ur_type": "ur5e"})
        with pytest.raises(DescriptionError, match="not UTF-8"):
            world.spawn("bob", model=str(binary))
        with pytest.raises(PackageNotFound, match="no_pkg"):
            world.spawn("bob", model="package://no_pkg/arm.urdf")
        assert world.arms == {}


def test_the_cli_spawns_a_file_with_xacro_arguments_and_a_package_path(
    workspace: Path, tmp_path: Path
) -> None:
    model = workspace / "my_arm_description" / "urdf" / "my_arm.urdf.xacro"
    result = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "spawn", "bob", "--at", "0,0",
         "--model", str(model), "--xacro-arg", "reach:=short", "--package-path",
         str(workspace), "--no-viewer", "--new-world", "--no-api", "--fast",
         "--duration", "0.2"],
        capture_output=True, text=True, timeout=120, check=False,
        env={**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "[bob] ready" in result.stdout
    refused = subprocess.run(
        [sys.executable, "-m", "armfleet.cli.main", "spawn", "bob", "--at", "0,0",
         "--model", str(model), "--no-viewer", "--new-world", "--no-api"],
        capture_output=True, text=True, timeout=120, check=False,
        env={**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)},
    )  # fmt: skip
    assert refused.returncode == 2
    lines = refused.stderr.strip().splitlines()
    assert len(lines) == 1 and "my_parts" in lines[0] and "--package-path" in lines[0], lines


def test_a_vendor_arm_plans_around_a_box_in_its_way_without_touching_it() -> None:
    """The planner takes a file's arm as a shipped one: with a box where its tool would pass
    halfway through a straight swing, a planned move arrives and touches nothing."""
    with armfleet.World() as world:
        bob = world.spawn("bob", model=str(UPSTREAM["ur5"]), at=(0, 0))
        start = np.asarray(bob.positions)
        goal = start.copy()
        goal[0] += 1.6  # swing the shoulder
        tool = world.tf.lookup("world", "bob_tool0")[:3, 3]
        half = 0.8
        turn = np.array(
            [[np.cos(half), -np.sin(half), 0], [np.sin(half), np.cos(half), 0], [0, 0, 1]]
        )
        midway = turn @ tool  # where the tool passes halfway through the straight swing
        world.add_object("box", "box", size=(0.12, 0.12, 0.12), mass=0.0, at=tuple(midway))
        contacts_before = world.contacts.total_contacts
        bob.move_to(goal, avoid_collisions=True, timeout_s=10.0)
        while bob.is_moving:
            world.run(0.05)
        world.run(0.2)
        assert np.abs(bob.positions - goal).max() < TRACKING_RAD
        assert bob.mode is armfleet.ArmMode.HOLDING
        assert world.contacts.total_contacts == contacts_before


def test_a_find_cycle_is_one_line_naming_the_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A file that includes itself through ``$(find)`` of its own package."""
    package = tmp_path / "loop_description"
    _write(package / "package.xml", "<package><name>loop_description</name></package>")
    arm = _write(
        package / "urdf" / "arm.urdf.xacro",
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:include filename="$(find loop_description)/urdf/arm.urdf.xacro"/></robot>',
    )
    monkeypatch.setenv("ARMFLEET_PACKAGE_PATH", str(tmp_path))
    with armfleet.World() as world, pytest.raises(DescriptionError) as caught:
        world.spawn("bob", model=str(arm))
    message = str(caught.value)
    assert "include cycle" in message and "arm.urdf.xacro" in message, message
    assert "\n" not in message


@pytest.fixture
def hard_parts(workspace: Path) -> Path:
    """The workspace with every hard part together in one more arm and a gripper package:
    ``my_turning_arm.urdf.xacro`` (a continuous base joint, a link drawn and collided with
    a COLLADA cube in centimetres, scaled by the URDF to 0.2 x 0.2 x 0.1 m, the joint
    limits from ``xacro.load_yaml``, ``my_parts``' macro through ``$(find)``, a
    ``<ros2_control>`` block, no tool0), and ``my_gripper_description`` (two prismatic
    fingers, the second a ``<mimic>`` of the first, their travel a xacro argument)."""
    _write(workspace / "my_parts" / "meshes" / "cube.dae", collada_cube(0.01))
    arm = workspace / "my_arm_description" / "urdf" / "my_turning_arm.urdf.xacro"
    _write(
        arm,
        """
        <?xml version="1.0"?>
        <robot name="my_turning_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:property name="limits"
              value="${xacro.load_yaml('$(find my_arm_description)/config/limits.yaml')}"/>
          <xacro:include filename="$(find my_parts)/urdf/parts.xacro"/>
          <link name="base">
            <visual><geometry>
              <mesh filename="package://my_parts/meshes/cube.dae" scale="20 20 10"/>
            </geometry></visual>
            <collision><geometry>
              <mesh filename="package://my_parts/meshes/cube.dae" scale="20 20 10"/>
            </geometry></collision>
            <inertial><mass value="3"/>
              <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.03"/></inertial>
          </link>
          <xacro:three_links p=""/>
          <joint name="turn" type="continuous">
            <parent link="base"/><child link="link1"/><origin xyz="0 0 0.05"/>
            <axis xyz="0 0 1"/><limit effort="${limits['effort']}" velocity="2.0"/>
          </joint>
          <joint name="shoulder" type="revolute">
            <parent link="link1"/><child link="link2"/><origin xyz="0 0 0.3"/>
            <axis xyz="0 1 0"/>
            <limit lower="${-limits['range']}" upper="${limits['range']}"
                   effort="${limits['effort']}" velocity="${limits['velocity']}"/>
          </joint>
          <joint name="elbow" type="revolute">
            <parent link="link2"/><child link="link3"/><origin xyz="0 0 0.3"/>
            <axis xyz="0 1 0"/>
            <limit lower="${-limits['range']}" upper="${limits['range']}"
                   effort="${limits['effort']}" velocity="${limits['velocity']}"/>
          </joint>
          <ros2_control name="my_turning_arm" type="system">
            <hardware><plugin>mock_components/GenericSystem</plugin></hardware>
            <joint name="turn"><command_interface name="position"/></joint>
          </ros2_control>
        </robot>
        """,
    )
    gripper = workspace / "my_gripper_description"
    _write(gripper / "package.xml", "<package><name>my_gripper_description</name></package>")
    palm = _box_link("palm", "0.1 0.1 0.02", 0.3, "0 0 0.01")
    fingers = "".join(
        _box_link(f"{side}_finger", "0.01 0.01 0.05", 0.05, "0 0 0.045") for side in "lr"
    )
    _write(
        gripper / "urdf" / "gripper.urdf.xacro",
        f"""
        <?xml version="1.0"?>
        <robot name="my_gripper" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:arg name="travel" default="0.04"/>{palm}{fingers}
          <joint name="l_finger_joint" type="prismatic">
            <parent link="palm"/><child link="l_finger"/><origin xyz="0.0 0 0.02"/>
            <axis xyz="1 0 0"/>
            <limit lower="0" upper="$(arg travel)" effort="20" velocity="0.2"/>
          </joint>
          <joint name="r_finger_joint" type="prismatic">
            <parent link="palm"/><child link="r_finger"/><origin xyz="0.0 0 0.02"/>
            <axis xyz="-1 0 0"/>
            <limit lower="0" upper="$(arg travel)" effort="20" velocity="0.2"/>
            <mimic joint="l_finger_joint" multiplier="1" offset="0"/>
          </joint>
        </robot>
        """,
    )
    return arm


def test_every_hard_part_together_by_path_with_an_end_effector(
    workspace: Path, hard_parts: Path
) -> None:
    models = ModelLibrary(package_paths=[workspace])
    effector = {
        "file": "package://my_gripper_description/urdf/gripper.urdf.xacro",
        "xacro_args": {"travel": "0.03"},
    }
    with armfleet.World(models=models) as world:
        bob = world.spawn("bob", model=str(hard_parts), at=(0, 0), end_effector=effector)
        toby = world.spawn("toby", model=str(hard_parts), at=(1.5, 0), end_effector=effector)
        for arm in (bob, toby):
            prefix = f"{arm.name}_"
            assert arm.joint_names == tuple(prefix + j for j in ("turn", "shoulder", "elbow"))
            assert arm.description.gripper_joints == (
                f"{prefix}l_finger_joint",
                f"{prefix}r_finger_joint",
            )
            assert "ros2_control" not in arm.description.urdf
        # The continuous joint has no position limit; the others come from the YAML.
        lower, upper = bob.joint_limits
        assert lower[0] == -np.inf and upper[0] == np.inf
        assert np.allclose(lower[1:], -2.5) and np.allclose(upper[1:], 2.5)
        # No tool0 in the file: the arm's chain ends at link3, the gripper hangs there.
        assert np.abs(world.tf.lookup("bob_link3", "bob_tool0") - np.eye(4)).max() < 1e-12
        assert world.tf.lookup("bob_link3", "bob_palm")[2, 3] == pytest.approx(0.0)
        # The COLLADA cube: 1 cm units, scaled 20 x 20 x 10 -> 0.2 x 0.2 x 0.1 m (+ margin).
        low, high = p.getAABB(bob.body.body_id, -1, physicsClientId=world.physics_client)
        assert np.subtract(high, low) == pytest.approx((0.202, 0.202, 0.102), abs=2e-3)
        # The base turns on past pi; the gripper's travel (a xacro argument) is its width.
        target = np.asarray(bob.positions)
        target[0] = 4.0
        bob.move_to(target)
        bob.gripper.move_to(0.05)  # two fingers of 0.03 m travel: at most 0.06 m
        world.run(4.0)
        assert abs(bob.positions[0] - 4.0) < TRACKING_RAD
        assert bob.gripper.max_width == pytest.approx(0.06)
        assert bob.gripper.width == pytest.approx(0.05, abs=5e-4)
        state = world.arm("bob").body.position
        names = bob.kinematics.joint_names
        left = state[names.index("bob_l_finger_joint")]
        right = state[names.index("bob_r_finger_joint")]
        assert abs(left - right) < 1e-4  # the mimic follows its leader


def test_the_planners_shapes_are_pybullets_size_for_a_collada_unit(
    workspace: Path, hard_parts: Path
) -> None:
    """The base's COLLADA cube is in centimetres: PyBullet applies the unit, coal's mesh
    loader does not (it loaded the cube 100 times too large, so every link was "inside"
    the base for the planner and for move_to's self-contact proof)."""
    import coal
    import pinocchio as pin

    from armfleet.planning.scene import arm_geometry

    with armfleet.World(models=ModelLibrary(package_paths=[workspace])) as world:
        bob = world.spawn("bob", model=str(hard_parts), at=(0, 0))
        low, high = p.getAABB(bob.body.body_id, -1, physicsClientId=world.physics_client)
        geometry = arm_geometry(
            "bob", bob.description.urdf, bob.kinematics.model, bob.joint_names, (), ()
        ).geometry
        base = next(g for g in geometry.geometryObjects if g.meshPath.endswith("cube.dae"))
        shape = base.geometry
        shape.computeLocalAABB()
        size = np.asarray(shape.aabb_local.max_) - np.asarray(shape.aabb_local.min_)
        assert isinstance(shape, coal.CollisionGeometry) and isinstance(base, pin.GeometryObject)
        # 1 cm units scaled 20 x 20 x 10; PyBullet's box is that grown by its margins.
        assert size == pytest.approx((0.2, 0.2, 0.1), abs=1e-9)
        assert np.subtract(high, low) - size == pytest.approx((0.0, 0.0, 0.0), abs=5e-3)
        target = np.asarray(bob.positions)
        target[0] = 1.0
        bob.move_to(target)  # refused as touching itself while the cube was 20 m wide
