"""Robot descriptions: models derived from description/, prefixed URDF, one resolver.

The expanded URDF is parsed with xml.etree and checked against the rules of
DESIGN.md ("Names") and against the upstream example-robot-data file it takes
its meshes, inertias and limits from.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

import pytest

from armfleet.description import ModelLibrary, ResourceResolver
from armfleet.description.data_folders import DATA_FOLDERS, data_dir
from armfleet.description.model_library import UPSTREAM_PROPERTY, XACRO_SUFFIX
from armfleet.description.package_finder import PACKAGE_PATH_ENV
from armfleet.description.resource_resolver import default_share_dirs
from armfleet.description.upstream_macro import XACRO_NS
from armfleet.errors import DescriptionError, ResourceNotFound, UnknownModel
from armfleet.frames.spawn_pose import SpawnPose

REPO_ROOT = Path(__file__).resolve().parents[1]
PREFIX = "bob_"
#: A raised, turned and tilted base: every component of xyz and rpy is non-zero.
POSE = SpawnPose(0.5, -1.25, 0.3, yaw_deg=90.0, roll_deg=10.0, pitch_deg=-20.0)
#: xacro writes the pose as text; reading it back loses nothing beyond float repr.
POSE_TOLERANCE = 1e-12
PANDA_UPSTREAM = "package://example-robot-data/robots/panda_description/urdf/panda.urdf"
MODEL_NAMES = ModelLibrary().names


@dataclass(frozen=True)
class Expanded:
    model: str
    robot: ET.Element
    text: str

    def links(self) -> dict[str, ET.Element]:
        return {link.get("name", ""): link for link in self.robot.findall("link")}

    def joints(self) -> dict[str, ET.Element]:
        return {joint.get("name", ""): joint for joint in self.robot.findall("joint")}


@pytest.fixture(scope="module", params=MODEL_NAMES)
def expanded(request: pytest.FixtureRequest) -> Expanded:
    """Each model expanded for arm ``bob`` at :data:`POSE`."""
    model = request.param
    description = ModelLibrary().expand(model, PREFIX, POSE)
    assert description.model == model and description.prefix == PREFIX
    return Expanded(model, ET.fromstring(description.urdf), description.urdf)


def upstream_of(model: str) -> ET.Element:
    """The upstream URDF a model's xacro names, parsed."""
    xacro_root = ET.parse(data_dir("description") / f"{model}{XACRO_SUFFIX}").getroot()
    (uri,) = [
        p.get("value", "")
        for p in xacro_root.findall(f"{{{XACRO_NS}}}property")
        if p.get("name") == UPSTREAM_PROPERTY
    ]
    return ET.parse(ResourceResolver().resolve(uri)).getroot()


def numbers(element: ET.Element | None) -> dict[str, tuple[float, ...]]:
    """An element's attributes as numbers (``xyz="0 1 2"`` -> (0.0, 1.0, 2.0))."""
    assert element is not None
    return {key: tuple(float(v) for v in value.split()) for key, value in element.attrib.items()}


def vector(text: str | None) -> tuple[float, ...]:
    assert text is not None
    return tuple(float(v) for v in text.split())


# -- models come from the folder ----------------------------------------------------------


def test_model_list_is_the_folder(tmp_path: Path) -> None:
    library = ModelLibrary(folder=tmp_path)
    assert library.names == []
    (tmp_path / "notes.txt").write_text("not a model")
    (tmp_path / "half.urdf").write_text("<robot/>")
    shutil.copy(data_dir("description") / f"panda{XACRO_SUFFIX}", tmp_path / f"twin{XACRO_SUFFIX}")
    assert library.names == ["twin"]

    description = library.expand("twin", PREFIX)
    assert description.model == "twin"
    links = {link.get("name") for link in ET.fromstring(description.urdf).iter("link")}
    assert {"world", f"{PREFIX}base_link", f"{PREFIX}tool0"} <= links

    with pytest.raises(UnknownModel) as caught:
        library.expand("panda", PREFIX)  # not in this folder
    assert str(caught.value) == "model 'panda' not found; available: twin"


def test_shipped_models_are_the_shipped_files(models: ModelLibrary) -> None:
    files = sorted(
        p.name for p in data_dir("description").iterdir() if p.name.endswith(XACRO_SUFFIX)
    )
    assert [f"{name}{XACRO_SUFFIX}" for name in models.names] == files
    assert {"panda", "ur5"} <= set(models.names)  # issue #2 asks for at least these
    assert {"ur3", "ur10", "z1", "xarm7"} <= set(models.names)  # and issue #8 for these


# -- every model, expanded -----------------------------------------------------------------


def test_every_name_is_prefixed_but_world(expanded: Expanded) -> None:
    links = [link.get("name", "") for link in expanded.robot.iter("link")]
    joints = [joint.get("name", "") for joint in expanded.robot.iter("joint")]
    assert links.count("world") == 1
    assert [name for name in links if not name.startswith(PREFIX)] == ["world"]
    assert [name for name in joints if not name.startswith(PREFIX)] == []
    assert len(set(links)) == len(links) and len(set(joints)) == len(joints)
    for joint in expanded.robot.iter("joint"):
        for end in ("parent", "child"):
            element = joint.find(end)
            assert element is not None
            assert element.get("link") in links
        mimic = joint.find("mimic")
        if mimic is not None:
            assert mimic.get("joint") in joints


def test_links_form_one_tree_rooted_at_world(expanded: Expanded) -> None:
    parent_of: dict[str, str] = {}
    for joint in expanded.robot.iter("joint"):
        child = joint.find("child")
        parent = joint.find("parent")
        assert child is not None and parent is not None
        name = child.get("link", "")
        assert name not in parent_of, f"{name} has two parents"
        parent_of[name] = parent.get("link", "")
    for link in expanded.links():
        seen = [link]
        while seen[-1] != "world":
            assert seen[-1] in parent_of, f"{link} does not hang from world"
            seen.append(parent_of[seen[-1]])
            assert len(seen) < 100, "cycle"


def test_world_joint_carries_the_spawn_pose(expanded: Expanded) -> None:
    anchors = [
        j for j in expanded.robot.iter("joint") if j.find("parent[@link='world']") is not None
    ]
    assert len(anchors) == 1
    (anchor,) = anchors
    assert anchor.get("type") == "fixed"
    child = anchor.find("child")
    assert child is not None and child.get("link") == f"{PREFIX}base_link"
    origin = anchor.find("origin")
    assert origin is not None
    xyz, rpy = vector(origin.get("xyz")), vector(origin.get("rpy"))
    for got, want in zip(xyz + rpy, (POSE.x, POSE.y, POSE.z, *POSE.rpy_rad), strict=True):
        assert abs(got - want) < POSE_TOLERANCE


def test_landmark_frames_exist(expanded: Expanded) -> None:
    links = expanded.links()
    assert f"{PREFIX}base_link" in links
    assert f"{PREFIX}tool0" in links
    # tool0 hangs below base_link.
    parent_of = {
        j.find("child").get("link"): j.find("parent").get("link")  # type: ignore[union-attr]
        for j in expanded.robot.iter("joint")
    }
    frame: str | None = f"{PREFIX}tool0"
    while frame not in (None, f"{PREFIX}base_link"):
        frame = parent_of.get(frame)
    assert frame == f"{PREFIX}base_link"


def test_every_uri_is_an_existing_absolute_file(expanded: Expanded) -> None:
    assert "package://" not in expanded.text
    assert "file://" not in expanded.text
    meshes = [mesh.get("filename", "") for mesh in expanded.robot.iter("mesh")]
    assert meshes, "a model without meshes draws nothing"
    for filename in meshes:
        assert Path(filename).is_absolute(), filename
        assert Path(filename).is_file(), filename


def test_no_link_lacks_inertia_but_world(expanded: Expanded) -> None:
    """PyBullet gives a link without <inertial> 1 kg; Pinocchio gives it none."""
    for name, link in expanded.links().items():
        inertial = link.find("inertial")
        if name == "world":
            assert inertial is None
            continue
        assert inertial is not None, name
        assert inertial.find("mass") is not None, name
        assert inertial.find("inertia") is not None, name


def test_inertias_limits_and_meshes_are_the_upstream_ones(expanded: Expanded) -> None:
    upstream = upstream_of(expanded.model)
    links, joints = expanded.links(), expanded.joints()
    compared_links = compared_joints = 0
    # Direct children only: <transmission> elements name joints too.
    for link in upstream.findall("link"):
        name = link.get("name", "")
        if name == "world":
            continue
        ours = links[PREFIX + name]
        if link.find("inertial") is not None:
            for tag in ("mass", "origin", "inertia"):
                assert numbers(ours.find(f"inertial/{tag}")) == numbers(
                    link.find(f"inertial/{tag}")
                ), (name, tag)
            compared_links += 1
        upstream_meshes = [Path(m.get("filename", "")).name for m in link.iter("mesh")]
        assert [Path(m.get("filename", "")).name for m in ours.iter("mesh")] == upstream_meshes
    for joint in upstream.findall("joint"):
        parent = joint.find("parent")
        if parent is not None and parent.get("link") == "world":
            continue  # replaced by our own world anchor
        ours = joints[PREFIX + joint.get("name", "")]
        assert ours.get("type") == joint.get("type")
        for tag in ("limit", "dynamics", "origin", "axis"):
            if joint.find(tag) is not None:
                assert numbers(ours.find(tag)) == numbers(joint.find(tag)), (joint.get("name"), tag)
        compared_joints += 1
    assert compared_links > 0 and compared_joints > 0


def test_panda_numbers_come_from_example_robot_data(models: ModelLibrary) -> None:
    upstream_path = ResourceResolver().resolve(PANDA_UPSTREAM)
    assert upstream_path.is_absolute() and upstream_path.is_file()
    upstream = ET.parse(upstream_path).getroot()
    ours = ET.fromstring(models.expand("panda", PREFIX).urdf)

    def find(root: ET.Element, tag: str, name: str) -> ET.Element:
        (element,) = [e for e in root.iter(tag) if e.get("name") == name]
        return element

    limit = numbers(find(ours, "joint", f"{PREFIX}panda_joint4").find("limit"))
    assert limit == numbers(find(upstream, "joint", "panda_joint4").find("limit"))
    assert limit["upper"][0] < 0.0  # joint4 of a Panda never straightens
    mass = numbers(find(ours, "link", f"{PREFIX}panda_link3").find("inertial/mass"))
    assert mass == numbers(find(upstream, "link", "panda_link3").find("inertial/mass"))
    assert mass["value"][0] > 1.0  # [kg]: a real link, not a placeholder


# -- the resolver --------------------------------------------------------------------------


def test_resolver_searches_folders_in_order(tmp_path: Path) -> None:
    first, second = tmp_path / "first", tmp_path / "second"
    (second / "pkg" / "meshes").mkdir(parents=True)
    (second / "pkg" / "meshes" / "part.stl").write_text("solid part\nendsolid part\n")
    resolver = ResourceResolver([first, second])
    found = resolver.resolve("package://pkg/meshes/part.stl")
    assert found == (second / "pkg" / "meshes" / "part.stl").resolve()
    (first / "pkg" / "meshes").mkdir(parents=True)
    (first / "pkg" / "meshes" / "part.stl").write_text("solid part\nendsolid part\n")
    assert resolver.resolve("package://pkg/meshes/part.stl").is_relative_to(first.resolve())


def test_missing_package_lists_every_folder_searched(tmp_path: Path) -> None:
    folders = [tmp_path / "first", tmp_path / "second"]
    uri = "package://nowhere/meshes/part.stl"
    with pytest.raises(ResourceNotFound) as caught:
        ResourceResolver(folders).resolve(uri)
    error = caught.value
    assert isinstance(error, DescriptionError)
    assert error.uri == uri
    assert error.searched == tuple(str(f) for f in folders)
    message = str(error)
    assert "\n" not in message and uri in message
    for folder in folders:
        assert str(folder) in message


def test_default_resolver_searches_the_environment_then_example_robot_data(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    extra = [tmp_path / "mine", tmp_path / "theirs"]
    monkeypatch.setenv(PACKAGE_PATH_ENV, os.pathsep.join(str(e) for e in extra))
    share_dirs = default_share_dirs()
    assert share_dirs[:2] == extra
    assert any((d / "example-robot-data").is_dir() for d in share_dirs[2:])
    resolver = ResourceResolver()
    with pytest.raises(ResourceNotFound) as caught:
        resolver.resolve("package://nowhere/x.stl")
    # The package finder's places (docs/own-robot.md): the environment's first, each named.
    assert caught.value.searched == tuple(str(place) for place in resolver.finder.places)
    assert [place.folder for place in resolver.finder.places][:2] == extra


def test_missing_file_uri_names_its_folder(tmp_path: Path) -> None:
    with pytest.raises(ResourceNotFound) as caught:
        ResourceResolver([tmp_path]).resolve(f"file://{tmp_path}/gone.stl")
    assert str(tmp_path) in str(caught.value)


def write_variant(folder: Path, name: str, old: str, new: str) -> Path:
    """Copy panda.urdf.xacro into ``folder`` as ``name``, with ``old`` replaced by ``new``."""
    text = (data_dir("description") / f"panda{XACRO_SUFFIX}").read_text()
    assert old in text
    path = folder / f"{name}{XACRO_SUFFIX}"
    path.write_text(text.replace(old, new, 1))
    return path


def test_missing_mesh_in_a_description_fails_loudly(tmp_path: Path) -> None:
    write_variant(
        tmp_path,
        "meshy",
        '<link name="world"/>',
        '<link name="world"/><link name="${prefix}extra"><visual><geometry>'
        '<mesh filename="package://nowhere/extra.stl"/></geometry></visual></link>'
        '<joint name="${prefix}extra_joint" type="fixed"><parent link="world"/>'
        '<child link="${prefix}extra"/></joint>',
    )
    library = ModelLibrary(folder=tmp_path)
    with pytest.raises(ResourceNotFound) as caught:
        library.expand("meshy", PREFIX)
    assert caught.value.uri == "package://nowhere/extra.stl"
    assert caught.value.searched == tuple(str(place) for place in library.resolver.finder.places)


def test_missing_upstream_urdf_fails_loudly(tmp_path: Path) -> None:
    write_variant(tmp_path, "orphan", PANDA_UPSTREAM, "package://nowhere/robot.urdf")
    with pytest.raises(ResourceNotFound) as caught:
        ModelLibrary(folder=tmp_path).expand("orphan", PREFIX)
    assert "package://nowhere/robot.urdf" in str(caught.value)


# -- malformed descriptions ----------------------------------------------------------------

MALFORMED = {
    # id: (text to replace, replacement, what the message must also say)
    "not-xml": ("</robot>", "", "not valid XML"),
    "unknown-macro": ('<link name="world"/>', "<xacro:no_such_macro/>", "no_such_macro"),
    "undefined-property":
        ('<link name="world"/>', '<link name="${no_such_property}"/>', "no_such_property"),
    "no-upstream-property":
        (f'name="{UPSTREAM_PROPERTY}"', 'name="something_else"', UPSTREAM_PROPERTY),
    "home-not-numbers": ('value="0 -0.785398', 'value="zero -0.785398', "armfleet_home"),
}  # fmt: skip


@pytest.mark.parametrize(
    "case",
    [
        pytest.param(
            key,
            id=key,
        )
        for key in MALFORMED
    ],
)
def test_malformed_description_names_its_file(tmp_path: Path, case: str) -> None:
    old, new, expected = MALFORMED[case]
    path = write_variant(tmp_path, "broken", old, new)
    with pytest.raises(DescriptionError) as caught:
        ModelLibrary(folder=tmp_path).expand("broken", PREFIX)
    message = str(caught.value)
    assert str(path) in message
    assert expected in message
    assert "\n" not in message


# -- the wheel ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """armfleet built as a wheel from this checkout, offline: the compiled fleet path
    (C++) is built too, reusing the editable install's build folder when it is there."""
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [
            sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
            "--no-index", "--disable-pip-version-check", "--quiet", "-w", str(out),
            str(REPO_ROOT),
        ],
        check=True,
        capture_output=True,
        timeout=900,
        env={**os.environ, "ARMFLEET_QUIET_BUILD": "1"},  # no compile notice on the terminal
    )  # fmt: skip
    (built,) = out.glob("armfleet-*.whl")
    return built


def test_wheel_ships_the_data_folders(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    assert "armfleet/_data/description/panda.urdf.xacro" in names
    assert "armfleet/_data/controllers/position_controller.yaml" in names
    for folder in DATA_FOLDERS:
        source = REPO_ROOT / folder
        for path in source.rglob("*"):
            if path.is_file():
                assert f"armfleet/_data/{folder}/{path.relative_to(source).as_posix()}" in names


def test_installed_wheel_finds_its_data_without_the_source_tree(
    wheel: Path, tmp_path: Path
) -> None:
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(tmp_path / "site")
    probe = (
        # The editable install's import hook (scikit-build-core's) outranks PYTHONPATH:
        # without it, this Python sees only the unpacked wheel's armfleet.
        "import sys; sys.meta_path[:] = [f for f in sys.meta_path"
        " if not type(f).__module__.startswith('_editable_skbc_')];"
        "import armfleet, armfleet.description.data_folders as paths;"
        "from armfleet.description import ModelLibrary;"
        "print(armfleet.__file__); print(paths.data_dir('description'));"
        "print(' '.join(ModelLibrary().names))"
    )
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "site")}
    result = subprocess.run(
        [sys.executable, "-c", probe],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    package, description, names = result.stdout.splitlines()
    site = (tmp_path / "site").resolve()
    assert Path(package).resolve().is_relative_to(site)
    assert Path(description) == site / "armfleet" / "_data" / "description"
    assert names.split() == MODEL_NAMES
