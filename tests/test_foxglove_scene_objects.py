"""The world's objects in Foxglove's 3D panel: ``/scene_objects`` (foxglove.SceneUpdate).

The messages are decoded with ``protobuf`` from the schema the server advertises (a
FileDescriptorSet), not from armfleet's code, and compared with the objects the world
was given: shape, size, colour, frame, mesh bytes and scale.
"""

from __future__ import annotations

import base64
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

import armfleet
from armfleet.foxglove import FoxgloveServer
from tests.test_foxglove import WAIT_S, FoxgloveClient, _step
from tests.test_objects import write_cube_stl

TOPIC = "/scene_objects"
#: foxglove.SceneEntityDeletion.type
MATCHING_ID, ALL = 0, 1


def scene_update_class(channel: dict[str, Any]) -> Any:
    """The message class of the channel's advertised protobuf schema."""
    assert channel["encoding"] == "protobuf"
    assert channel["schemaEncoding"] == "protobuf"
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


@pytest.fixture
def scene(tmp_path: Path) -> Iterator[tuple[armfleet.World, FoxgloveServer, Path]]:
    """bob, a static table, a can, a ball and a mesh brick, stepping at the wall clock."""
    brick = write_cube_stl(tmp_path / "brick.stl", 25.0)  # mm, scaled to 5 cm
    world = armfleet.World()
    world.spawn("bob", at=(0, 0))
    world.add_object("table", "box", size=(0.3, 0.4, 0.15), mass=0, at=(0.6, 0, 0.075))
    world.add_object("can", "cylinder", size=(0.03, 0.1), mass=0.1, at=(0.6, 0.1, 0.2))
    world.add_object("ball", "sphere", size=(0.02,), mass=0.05, at=(0.6, -0.1, 0.2))
    world.add_object(
        "brick", "mesh", mesh=brick, scale=0.001, mass=0.1, at=(0.5, 0, 0.2),
        color=(0.2, 0.4, 0.6, 1.0),
    )  # fmt: skip
    stop = threading.Event()
    stepper = threading.Thread(target=_step, args=(world, stop), daemon=True)
    server = world.serve_foxglove(0)
    stepper.start()
    try:
        yield world, server, brick
    finally:
        stop.set()
        stepper.join(timeout=10)
        world.close()


def test_objects_are_drawn_as_their_shapes_in_their_frames(
    scene: tuple[armfleet.World, FoxgloveServer, Path],
) -> None:
    world, server, brick_file = scene
    client = FoxgloveClient.open(server.url)
    channel = client.channels[TOPIC]
    assert channel["schemaName"] == "foxglove.SceneUpdate"
    update_class = scene_update_class(channel)
    client.subscribe(TOPIC)
    client.wait_for(lambda: bool(client.messages[TOPIC]))
    update = update_class.FromString(client.messages[TOPIC][0].data)
    assert [d.type for d in update.deletions] == [ALL]  # whatever it showed before
    entities = {e.id: e for e in update.entities}
    objects = world.submit(lambda: dict(world.objects)).result(timeout=WAIT_S)
    assert set(entities) == set(objects) == {"table", "can", "ball", "brick"}
    for name, entity in entities.items():
        assert entity.frame_id == name  # TF's world -> <object>: drawn where the object is
        assert entity.frame_locked
        drawn = [*entity.cubes, *entity.cylinders, *entity.spheres, *entity.models]
        assert len(drawn) == 1
        color = drawn[0].color
        assert (color.r, color.g, color.b, color.a) == pytest.approx(objects[name].color)
    (table,) = entities["table"].cubes
    assert (table.size.x, table.size.y, table.size.z) == pytest.approx((0.3, 0.4, 0.15))
    (can,) = entities["can"].cylinders
    assert (can.size.x, can.size.y, can.size.z) == pytest.approx((0.06, 0.06, 0.1))
    assert can.bottom_scale == can.top_scale == 1.0  # a cylinder, not a cone
    (ball,) = entities["ball"].spheres
    assert (ball.size.x, ball.size.y, ball.size.z) == pytest.approx((0.04, 0.04, 0.04))
    (brick,) = entities["brick"].models
    assert brick.data == brick_file.read_bytes()
    assert brick.media_type == "model/stl"
    assert brick.override_color
    assert (brick.scale.x, brick.scale.y, brick.scale.z) == pytest.approx((0.001,) * 3)
    client.close()


def test_objects_added_and_removed_while_watched_are_updated(
    scene: tuple[armfleet.World, FoxgloveServer, Path],
) -> None:
    world, server, _ = scene
    client = FoxgloveClient.open(server.url)
    update_class = scene_update_class(client.channels[TOPIC])
    client.subscribe(TOPIC)
    client.wait_for(lambda: bool(client.messages[TOPIC]))

    def change() -> None:
        world.remove_object("ball")
        world.add_object("crate", "box", size=(0.1, 0.1, 0.1), mass=0, at=(-0.6, 0, 0.05))

    world.submit(change).result(timeout=WAIT_S)
    client.wait_for(lambda: len(client.messages[TOPIC]) >= 2)  # on the next status tick
    update = update_class.FromString(client.messages[TOPIC][1].data)
    assert [(d.type, d.id) for d in update.deletions] == [(MATCHING_ID, "ball")]
    assert [e.id for e in update.entities] == ["crate"]
    (crate,) = update.entities[0].cubes
    assert (crate.size.x, crate.size.y, crate.size.z) == pytest.approx((0.1, 0.1, 0.1))
    client.close()
