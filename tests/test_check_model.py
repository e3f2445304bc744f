"""``armfleet check-model`` and the problems a description is refused for at load
(armfleet/description/model_problems.py, mesh_readability.py, include_cycle.py)."""

from __future__ import annotations

import re
import subprocess
import sys
import sysconfig
import textwrap
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.errors import DescriptionError

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"
VENDOR_FILES = {
    "ur5": ROBOTS / "ur_description/urdf/ur5_robot.urdf",
    "so100": ROBOTS / "so_arm_description/urdf/so100.urdf",
}
ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")
#: check-model prints limits to 6 significant digits.
PRINTED_REL = 1e-5
#: Every arm joint tracks the test move to this once settled [rad] (tests/test_own_robot.py).
TRACKING_RAD = 1e-3
#: A ray hits a convex mesh within this of its surface [m] (PyBullet's ray test is exact
#: to float precision; a unit left unapplied would be off by the size itself).
RAY_TOLERANCE_M = 1e-4
#: Bullet's collision margin around a mesh's convex hull [m] (its URDF importer's
#: ``gUrdfDefaultCollisionMargin``): a ray meets the shape this far outside the faces.
MESH_MARGIN_M = 0.001


def _check_model(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*ARMFLEET, "check-model", *args], capture_output=True, text=True, timeout=300
    )


def _printed_joints(stdout: str) -> dict[str, tuple[str, tuple[float, float] | None]]:
    """The joint table check-model printed: name -> (type, (lower, upper) or None)."""
    block = stdout.split("joints (", 1)[1].split("\narm joints:", 1)[0].splitlines()[1:]
    joints = {}
    for line in block:
        name, kind, *rest = line.split()
        bounds = re.match(r"\[(\S+), (\S+)\]", " ".join(rest))
        limits = (float(bounds.group(1)), float(bounds.group(2))) if bounds else None
        joints[name] = (kind, limits)
    return joints


@pytest.mark.parametrize("name", sorted(VENDOR_FILES))
def test_check_model_prints_the_joints_of_the_file_and_a_tracked_test_move(name: str) -> None:
    result = _check_model(str(VENDOR_FILES[name]))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    printed = _printed_joints(result.stdout)
    expected = {}  # the file read independently
    for joint in ET.parse(VENDOR_FILES[name]).getroot().findall("joint"):
        limit = joint.find("limit")
        kind = joint.get("type", "")
        bounds = None
        if kind in ("revolute", "prismatic") and limit is not None:
            bounds = (float(limit.get("lower", "0")), float(limit.get("upper", "0")))
        expected[joint.get("name", "")] = (kind, bounds)
    assert printed.keys() == expected.keys()
    for joint_name, (kind, bounds) in expected.items():
        assert printed[joint_name][0] == kind, joint_name
        if bounds is None:
            assert printed[joint_name][1] is None, joint_name
        else:
            assert printed[joint_name][1] == pytest.approx(bounds, rel=PRINTED_REL, abs=1e-12), (
                joint_name
            )
    move = re.search(r"test move: .* largest error (\S+)", result.stdout)
    assert move is not None, result.stdout
    assert float(move.group(1)) < TRACKING_RAD
    assert "problems: none" in result.stdout


def _write(path: Path, text: str | bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(textwrap.dedent(text).lstrip())
    return path


def _inertial(mass: float, ixx: float = 0.01) -> str:
    return (
        f'<inertial><mass value="{mass}"/><inertia ixx="{ixx}" ixy="0" ixz="0" iyy="0.01" '
        'iyz="0" izz="0.01"/></inertial>'
    )


def _arm(link2: str, extra: str = "") -> str:
    """A two-joint arm whose second moving link is ``link2`` (its inside)."""
    return f"""
        <?xml version="1.0"?>
        <robot name="bad" xmlns:xacro="http://www.ros.org/wiki/xacro">{extra}
          <link name="base_link">{_inertial(2.0)}
            <collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry>
            </collision></link>
          <link name="link1">{_inertial(1.0)}
            <collision><origin xyz="0 0 0.15"/><geometry><box size="0.05 0.05 0.3"/></geometry>
            </collision></link>
          <link name="link2">{link2}</link>
          <joint name="joint1" type="revolute"><parent link="base_link"/><child link="link1"/>
            <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
            <limit lower="-2" upper="2" effort="50" velocity="2"/></joint>
          <joint name="joint2" type="revolute"><parent link="link1"/><child link="link2"/>
            <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
            <limit lower="-2" upper="2" effort="50" velocity="2"/></joint>
        </robot>
        """


def _mesh_link(filename: str, scale: str = "") -> str:
    scaled = f' scale="{scale}"' if scale else ""
    return f"""{_inertial(0.5)}
        <collision><origin xyz="0 0 0.2"/>
          <geometry><mesh filename="{filename}"{scaled}/></geometry></collision>"""


def _massless_leaf(folder: Path) -> tuple[Path, str]:
    return _write(folder / "arm.urdf", _arm("")), "link 'link2' is moved by revolute joint"


def _negative_inertia(folder: Path) -> tuple[Path, str]:
    path = _write(folder / "arm.urdf", _arm(_inertial(0.5, ixx=-0.01)))
    return path, "link 'link2' has an inertia tensor that is not positive"


def _missing_mesh(folder: Path) -> tuple[Path, str]:
    path = _write(folder / "arm.urdf", _arm(_mesh_link("meshes/gone.stl")))
    return path, "link 'link2': collision mesh"


def _empty_stl(folder: Path) -> tuple[Path, str]:
    _write(folder / "meshes" / "empty.stl", b"")
    path = _write(folder / "arm.urdf", _arm(_mesh_link("meshes/empty.stl")))
    return path, "empty.stl' is empty"


def _garbage_dae(folder: Path) -> tuple[Path, str]:
    _write(folder / "meshes" / "garbage.dae", b"\x00\x01 not COLLADA at all")
    path = _write(folder / "arm.urdf", _arm(_mesh_link("meshes/garbage.dae")))
    return path, "garbage.dae' is no COLLADA file"


def _dae_without_geometry(folder: Path) -> tuple[Path, str]:
    # PyBullet 3.2 crashes (segmentation fault) on this one: it must never get it.
    _write(folder / "meshes" / "hollow.dae", collada_cube(None, with_geometry=False))
    path = _write(folder / "arm.urdf", _arm(_mesh_link("meshes/hollow.dae")))
    return path, "hollow.dae' is a COLLADA file with no mesh geometry"


def _include_cycle(folder: Path) -> tuple[Path, str]:
    _write(
        folder / "parts.xacro",
        """
        <robot xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:include filename="arm.urdf.xacro"/>
        </robot>
        """,
    )
    include = '\n  <xacro:include filename="parts.xacro"/>'
    path = _write(folder / "arm.urdf.xacro", _arm(_inertial(0.5), include))
    return path, "include cycle arm.urdf.xacro -> parts.xacro -> arm.urdf.xacro"


BAD = [
    pytest.param(_massless_leaf, id="a moving link with no mass"),
    pytest.param(_negative_inertia, id="an inertia tensor with a negative moment"),
    pytest.param(_missing_mesh, id="a mesh that is not there"),
    pytest.param(_empty_stl, id="an empty STL mesh"),
    pytest.param(_garbage_dae, id="a DAE mesh that is garbage"),
    pytest.param(_dae_without_geometry, id="a DAE mesh with no geometry"),
    pytest.param(_include_cycle, id="a xacro include cycle"),
]


@pytest.mark.parametrize("make", BAD)
def test_a_bad_description_is_one_line_from_check_model_and_refused_at_spawn(
    make: Callable[[Path], tuple[Path, str]], tmp_path: Path
) -> None:
    path, named = make(tmp_path)
    result = _check_model(str(path))
    assert result.returncode == 2, result.stdout
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], result.stderr
    with armfleet.World() as world:
        toby = world.spawn("toby", model=str(VENDOR_FILES["so100"]), at=(1.0, 0.0))
        client = world.physics_client
        bodies = p.getNumBodies(physicsClientId=client)
        with pytest.raises(DescriptionError) as refused:
            world.spawn("bob", model=str(path), at=(0.0, 0.0))
        assert "\n" not in str(refused.value) and named in str(refused.value)
        assert world.arms == {"toby": toby}
        assert p.getNumBodies(physicsClientId=client) == bodies
        # Nothing of bob was claimed: the name and its frames are free for a good arm.
        bob = world.spawn("bob", model=str(VENDOR_FILES["so100"]), at=(0.0, 0.0))
        assert bob.joint_names[0].startswith("bob_")


def collada_cube(unit_m: float | None, with_geometry: bool = True) -> str:
    """A cube of side 1 (file units), centred on its origin, as COLLADA."""
    corners = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    faces = "0 1 3 0 3 2 4 6 7 4 7 5 0 4 5 0 5 1 2 3 7 2 7 6 0 2 6 0 6 4 1 5 7 1 7 3"
    unit = f'<unit meter="{unit_m}" name="unit"/>' if unit_m is not None else ""
    geometry = f"""<library_geometries><geometry id="cube"><mesh>
      <source id="positions"><float_array id="values" count="24">
        {" ".join(f"{c}" for corner in corners for c in corner)}</float_array>
        <technique_common><accessor source="#values" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/>
          <param name="Z" type="float"/></accessor></technique_common></source>
      <vertices id="vertices"><input semantic="POSITION" source="#positions"/></vertices>
      <triangles count="12"><input semantic="VERTEX" source="#vertices" offset="0"/>
        <p>{faces}</p></triangles>
    </mesh></geometry></library_geometries>"""
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>{unit}<up_axis>Z_UP</up_axis></asset>
  {geometry if with_geometry else ""}
  <library_visual_scenes><visual_scene id="scene"><node id="node">
    {'<instance_geometry url="#cube"/>' if with_geometry else ""}
  </node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


@pytest.mark.parametrize(
    ("unit_m", "scale", "size"),
    [
        pytest.param(0.1, "", (0.1, 0.1, 0.1), id="a DAE in decimetres (<unit meter=0.1>)"),
        pytest.param(None, "0.1 0.2 0.3", (0.1, 0.2, 0.3), id="a DAE scaled by <mesh scale=...>"),
        pytest.param(0.1, "2 2 2", (0.2, 0.2, 0.2), id="a DAE with a unit and a scale"),
    ],
)
def test_a_scaled_dae_mesh_collides_at_its_scaled_size(
    tmp_path: Path, unit_m: float | None, scale: str, size: tuple[float, float, float]
) -> None:
    _write(tmp_path / "meshes" / "cube.dae", collada_cube(unit_m))
    path = _write(tmp_path / "arm.urdf", _arm(_mesh_link("meshes/cube.dae", scale)))
    with armfleet.World() as world:
        arm = world.spawn("bob", model=str(path), at=(0.0, 0.0))
        link = arm.body.link_world_pose("bob_link2")
        centre = link[:3, :3] @ np.array([0.0, 0.0, 0.2]) + link[:3, 3]
        client = world.physics_client
        # Rays from outside onto the faces, along the link's axes (not from below: the
        # arm is there), each meeting the cube half its size (and the margin) from its centre.
        for axis, sign in ((0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0)):
            start = centre + sign * link[:3, axis]
            hit = p.rayTest(start.tolist(), centre.tolist(), physicsClientId=client)[0]
            assert hit[0] == arm.body.body_id, f"the ray along axis {axis} missed the cube"
            measured = float(np.linalg.norm(np.asarray(hit[3]) - centre))
            expected = size[axis] / 2 + MESH_MARGIN_M
            assert measured == pytest.approx(expected, abs=RAY_TOLERANCE_M), axis
