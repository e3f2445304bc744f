"""A recording draws its arms on any machine: ``/<arm>/robot_meshes`` holds every link's
visual geometry with the mesh files inside (issue 28, item 16).

The file is read with the official ``mcap`` reader, its messages as JSON under the JSON
Schema the file holds, the way Foxglove's JSON reader does (a ``"contentEncoding":
"base64"`` string becomes bytes). The meshes are then parsed from those bytes alone, with
the small COLLADA and STL readers below, and compared with the source files they were
made from, read from disk independently.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import json
import struct
import xml.etree.ElementTree as ElementTree
from collections import defaultdict
from pathlib import Path
from typing import Any

import jsonschema  # type: ignore[import-untyped]
import numpy as np
import pytest
from mcap.exceptions import EndOfFile
from mcap.reader import NonSeekingReader, make_reader

import armfleet

#: The types Foxglove's JSON Schema reader (``@foxglove/mcap-support`` parseJsonSchema)
#: turns into message fields; anything else hides the channel.
FOXGLOVE_FIELD_TYPES = {"boolean", "string", "number", "integer", "object", "array"}


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A Panda (COLLADA meshes) and an xArm7 (STL meshes, URDF colours), recorded 0.1 s;
    what the file holds, read back from its bytes only."""
    path = tmp_path_factory.mktemp("meshes") / "run.mcap"
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        world.spawn("xena", model="xarm7", at=(1, 0))
        urdfs = {name: arm.description.urdf for name, arm in world.arms.items()}
        with armfleet.record(world, path):
            world.run(0.1)
    messages: dict[str, list[bytes]] = defaultdict(list)
    schemas: dict[str, Any] = {}
    with path.open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            messages[channel.topic].append(message.data)
            schemas[channel.topic] = (schema, channel)
    return {"urdfs": urdfs, "messages": messages, "schemas": schemas}


# -- independent readers of the mesh formats ---------------------------------------------------
def collada_vertices(data: bytes) -> np.ndarray:
    """Every vertex position of a COLLADA file's geometries (its own units), checking that
    every triangle index points at one."""
    root = ElementTree.fromstring(data)
    ns = {"c": root.tag.split("}")[0].strip("{")} if root.tag.startswith("{") else {"c": ""}
    prefix = "c:" if ns["c"] else ""
    points = []
    for mesh in root.iterfind(f".//{prefix}library_geometries/{prefix}geometry/{prefix}mesh", ns):
        arrays = {
            source.get("id"): source.find(f"{prefix}float_array", ns)
            for source in mesh.iterfind(f"{prefix}source", ns)
        }
        position = mesh.find(f"{prefix}vertices/{prefix}input[@semantic='POSITION']", ns)
        assert position is not None
        array = arrays[position.get("source", "").lstrip("#")]
        assert array is not None and array.text is not None
        values = np.array(array.text.split(), dtype=float)
        assert values.size == int(array.get("count", -1)) and values.size % 3 == 0
        vertices = values.reshape(-1, 3)
        for faces in [
            *mesh.iterfind(f"{prefix}triangles", ns),
            *mesh.iterfind(f"{prefix}polylist", ns),
        ]:
            inputs = faces.findall(f"{prefix}input", ns)
            stride = 1 + max(int(i.get("offset", 0)) for i in inputs)
            vertex_offset = next(
                int(i.get("offset", 0)) for i in inputs if i.get("semantic") == "VERTEX"
            )
            indices = np.array((faces.findtext(f"{prefix}p", "", ns)).split(), dtype=int)
            used = indices[vertex_offset::stride]
            assert used.size > 0 and used.max() < len(vertices)
        points.append(vertices)
    assert points, "no geometry"
    return np.concatenate(points)


def stl_vertices(data: bytes) -> np.ndarray:
    """Every triangle corner of an STL file (binary or ASCII)."""
    if data[:5] == b"solid" and b"facet" in data[:1000]:
        words = data.decode().split()
        values = [words[i + 1 : i + 4] for i, w in enumerate(words) if w == "vertex"]
        return np.array(values, dtype=float)
    (count,) = struct.unpack_from("<I", data, 80)
    assert len(data) == 84 + 50 * count, "a binary STL's size is 84 + 50 bytes per triangle"
    record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
    return np.frombuffer(data, record, count, 84)["corners"].reshape(-1, 3).astype(float)


def mesh_vertices(data: bytes, media_type: str) -> np.ndarray:
    if media_type == "model/vnd.collada+xml":
        return collada_vertices(data)
    assert media_type == "model/stl", media_type
    return stl_vertices(data)


def check_foxglove_reads(schema: dict[str, Any], where: str = "") -> None:
    """Every field has one type Foxglove's JSON Schema reader knows (it would hide the
    whole channel otherwise); bytes are base64 strings."""
    assert schema["type"] == "object", where
    for name, field in schema["properties"].items():
        assert field["type"] in FOXGLOVE_FIELD_TYPES, f"{where}.{name}"
        if field["type"] == "string":
            assert field.get("contentEncoding") in (None, "base64"), f"{where}.{name}"
        if field["type"] == "object":
            check_foxglove_reads(field, f"{where}.{name}")
        if field["type"] == "array":
            items = field["items"]
            assert items["type"] in FOXGLOVE_FIELD_TYPES - {"array"}, f"{where}.{name}"
            if items["type"] == "object":
                check_foxglove_reads(items, f"{where}.{name}[]")


def urdf_visual_links(urdf: str) -> dict[str, list[str]]:
    """Link -> its visual mesh files, from the URDF."""
    links: dict[str, list[str]] = {}
    for link in ElementTree.fromstring(urdf).iter("link"):
        meshes = [m.get("filename", "") for m in link.iterfind("visual/geometry/mesh")]
        if link.find("visual") is not None:
            links[link.get("name", "")] = meshes
    return links


# -- the tests -----------------------------------------------------------------------------------
@pytest.mark.parametrize("arm", ["bob", "xena"])
def test_every_visual_link_carries_its_mesh_inside_the_file(
    recording: dict[str, Any], arm: str
) -> None:
    topic = f"/{arm}/robot_meshes"
    schema, channel = recording["schemas"][topic]
    assert schema.name == "foxglove.SceneUpdate" and schema.encoding == "jsonschema"
    assert channel.message_encoding == "json"
    json_schema = json.loads(schema.data)
    check_foxglove_reads(json_schema)
    (data,) = recording["messages"][topic]
    update = json.loads(data)
    jsonschema.validate(update, json_schema)

    links = urdf_visual_links(recording["urdfs"][arm])
    entities = {entity["frame_id"]: entity for entity in update["entities"]}
    assert set(entities) == set(links)  # every link with a visual, nothing else
    for link, files in links.items():
        entity = entities[link]
        assert entity["frame_locked"] and entity["id"] == link
        models = entity["models"]
        assert len(models) == len(files)
        for model, file in zip(models, files, strict=True):
            assert model["url"] == ""  # nothing to fetch: the bytes are here
            embedded = base64.b64decode(model["data"], validate=True)
            source = Path(file).read_bytes()  # the source, read independently
            assert hashlib.sha256(embedded).digest() == hashlib.sha256(source).digest()
            vertices = mesh_vertices(embedded, model["media_type"])
            expected = mesh_vertices(source, model["media_type"])
            assert vertices.shape == expected.shape and len(vertices) >= 3
            np.testing.assert_array_equal(vertices.min(axis=0), expected.min(axis=0))
            np.testing.assert_array_equal(vertices.max(axis=0), expected.max(axis=0))
            assert np.all(np.isfinite(vertices))


def test_nothing_the_app_draws_refers_to_this_machine(recording: dict[str, Any]) -> None:
    """Opened elsewhere, the meshes need no file: no path or file:// URI in any mesh
    message, and every frame they hang on is in the recorded TF."""
    tf_frames = {
        transform["child_frame_id"]
        for topic in ("/tf", "/tf_static")
        for data in recording["messages"][topic]
        for transform in json.loads(data)["transforms"]
    }
    here = str(Path(armfleet.__file__).resolve().parents[1])
    for arm in ("bob", "xena"):
        (data,) = recording["messages"][f"/{arm}/robot_meshes"]
        update = json.loads(data)
        for entity in update["entities"]:
            assert entity["frame_id"] in tf_frames
            for model in entity["models"]:
                model.pop("data")
            text = json.dumps(entity)
            assert (
                "file://" not in text and here not in text and "/" not in text.replace("model/", "")
            ), text


def test_urdf_colours_are_kept(recording: dict[str, Any]) -> None:
    """The xArm7's URDF colours its STL meshes (STL has none); the Panda's COLLADA meshes
    carry their own, so the URDF's (none) does not override them."""
    for arm, overridden in (("xena", True), ("bob", False)):
        (data,) = recording["messages"][f"/{arm}/robot_meshes"]
        models = [m for e in json.loads(data)["entities"] for m in e["models"]]
        assert {m["override_color"] for m in models} == {overridden}


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's rpy: about fixed X, then Y, then Z (R = Rz Ry Rx)."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (np.cos, np.sin))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    rotation: np.ndarray = rz @ ry @ rx
    return rotation


def _quaternion_matrix(q: dict[str, float]) -> np.ndarray:
    x, y, z, w = q["x"], q["y"], q["z"], q["w"]
    matrix: np.ndarray = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    return matrix


def test_primitive_visuals_keep_their_origin_size_and_named_colour() -> None:
    from armfleet.recording.robot_meshes import ROBOT_MESHES, robot_meshes_message

    urdf = """<robot name="r">
      <material name="red"><color rgba="1 0 0 1"/></material>
      <link name="a"><visual><origin xyz="0.1 0.2 0.3" rpy="0.3 -0.2 1.1"/>
        <geometry><box size="0.1 0.2 0.3"/></geometry><material name="red"/></visual>
        <visual><geometry><cylinder radius="0.05" length="0.4"/></geometry></visual></link>
      <link name="b"><visual><geometry><sphere radius="0.07"/></geometry>
        <material name="blue"><color rgba="0 0 1 0.5"/></material></visual></link>
      <link name="c"/>
    </robot>"""
    update = json.loads(robot_meshes_message(urdf, 1_500_000_000))
    jsonschema.validate(update, json.loads(ROBOT_MESHES.data))
    entities = {e["frame_id"]: e for e in update["entities"]}
    assert set(entities) == {"a", "b"}  # c has nothing to draw
    (cube,) = entities["a"]["cubes"]
    assert cube["pose"]["position"] == {"x": 0.1, "y": 0.2, "z": 0.3}
    np.testing.assert_allclose(
        _quaternion_matrix(cube["pose"]["orientation"]), _rotation(0.3, -0.2, 1.1), atol=1e-12
    )
    assert cube["size"] == {"x": 0.1, "y": 0.2, "z": 0.3}
    assert cube["color"] == {"r": 1.0, "g": 0.0, "b": 0.0, "a": 1.0}
    (cylinder,) = entities["a"]["cylinders"]
    assert cylinder["size"] == {"x": 0.1, "y": 0.1, "z": 0.4}
    (sphere,) = entities["b"]["spheres"]
    assert sphere["size"] == {"x": 0.14, "y": 0.14, "z": 0.14}
    assert sphere["color"] == {"r": 0.0, "g": 0.0, "b": 1.0, "a": 0.5}
    assert entities["a"]["timestamp"] == {"sec": 1, "nsec": 500_000_000}


def test_the_recording_layout_names_only_what_a_recording_holds(tmp_path: Path) -> None:
    """docs/foxglove-recording-layout.json (for bob and toby) shows the embedded meshes,
    and no URDF layer (its file:// meshes would not load on another machine)."""
    path = tmp_path / "pair.mcap"
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        world.spawn("toby", at=(1, 0))
        with armfleet.record(world, path):
            world.run(0.05)
    with path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    recorded = {channel.topic for channel in summary.channels.values()}
    docs = Path(__file__).parents[1] / "docs"
    panels = json.loads((docs / "foxglove-recording-layout.json").read_text())["configById"]
    three = panels["3D!armfleet"]
    assert not [layer for layer in three["layers"].values() if layer["layerId"] == "foxglove.Urdf"]
    shown = {topic for topic, config in three["topics"].items() if config["visible"]}
    assert {"/bob/robot_meshes", "/toby/robot_meshes", "/tf", "/tf_static"} <= shown
    topics = set(three["topics"])
    topics |= {path["value"].split(".")[0] for path in panels["Plot!joints"]["paths"]}
    topics.add(panels["RawMessages!tf"]["topicPath"])
    assert topics <= recorded, topics - recorded


def test_the_meshes_are_written_as_the_file_completes_at_the_arm_s_time(tmp_path: Path) -> None:
    """Megabytes of meshes at the start would push the first seconds of data out of a run
    cut short: they are logged at the arm's arrival but written as the file is completed.
    A copy taken mid-run, as a kill -9 leaves it, holds the joint states and no meshes."""
    path, cut = tmp_path / "run.mcap", tmp_path / "cut.mcap"
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        start_ns = round(world.time * 1e9)  # the arm came before: logged at the start
        with armfleet.record(world, path):
            world.run(1.0)  # a few chunks written
            cut.write_bytes(path.read_bytes())
    topics = []
    with cut.open("rb") as stream, contextlib.suppress(EndOfFile):  # it ends cut
        for _, channel, _ in NonSeekingReader(stream).iter_messages(log_time_order=False):
            topics.append(channel.topic)
    assert topics.count("/bob/joint_states") > 100 and "/bob/robot_meshes" not in topics
    with path.open("rb") as stream:
        found = [
            (message.log_time, message.data)
            for _, channel, message in make_reader(stream).iter_messages()
            if channel.topic == "/bob/robot_meshes"
        ]
    assert len(found) == 1
    log_time, data = found[0]
    assert log_time == start_ns
    assert "bob_panda_link7" in {entity["frame_id"] for entity in json.loads(data)["entities"]}
