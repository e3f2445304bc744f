"""Foxglove live, proven with a real WebSocket client speaking the SDK's protocol.

The client below is the ``websockets`` package's, with subprotocol
``foxglove.sdk.v1``; the frame layouts are the ones measured in FIELD-NOTES. The world
steps in a thread of its own at the wall clock's pace, as a command-line run does.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import struct
import subprocess
import sys
import threading
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jsonschema  # type: ignore[import-untyped]
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

import armfleet
import armfleet.foxglove
from armfleet.foxglove import SERVICE_SCHEMAS, FoxgloveError, FoxgloveServer, urdf_uri
from armfleet.recording.encode import encoder_for

SUBPROTOCOL = Subprotocol("foxglove.sdk.v1")
#: Longest wait for anything the test expects [s] (the world runs at the wall clock).
WAIT_S = 10.0
TARGET = [0.3, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8]
#: Joint position error at which an arm has arrived [rad] (the controller holds ~1e-4).
ARRIVED_RAD = 5e-3


# -- a small client of the Foxglove SDK's WebSocket protocol -----------------------------
@dataclass
class Message:
    topic: str
    log_time_ns: int
    data: bytes

    @property
    def json(self) -> Any:
        return json.loads(self.data)


@dataclass
class FoxgloveClient:
    """Reads every frame into plain state: channels, services, messages, replies."""

    ws: ClientConnection
    server_info: dict[str, Any] = field(default_factory=dict)
    channels: dict[str, dict[str, Any]] = field(default_factory=dict)
    services: dict[str, dict[str, Any]] = field(default_factory=dict)
    unadvertised: list[int] = field(default_factory=list)
    messages: dict[str, list[Message]] = field(default_factory=lambda: defaultdict(list))
    replies: dict[int, tuple[bool, bytes | str]] = field(default_factory=dict)
    assets: dict[int, tuple[bool, bytes | str]] = field(default_factory=dict)
    times: list[int] = field(default_factory=list)
    _subscriptions: dict[int, str] = field(default_factory=dict)
    _next_id: int = 1

    @classmethod
    def open(cls, url: str) -> FoxgloveClient:
        ws = connect(
            url,
            subprotocols=[SUBPROTOCOL],
            proxy=None,
            max_size=None,
            max_queue=None,  # read everything as it comes: the close handshake is not held
            open_timeout=5,
            close_timeout=2,
            legacy=True,  # a plain connection, not a reconnecting iterator
        )
        client = cls(ws)
        client.wait_for(lambda: bool(client.server_info and client.channels and client.services))
        return client

    def close(self) -> None:
        self.ws.close()

    def pump(self, timeout: float = 0.1) -> None:
        """Read frames for at most ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                frame = self.ws.recv(timeout=left)
            except TimeoutError:
                return
            self._read(frame)

    def wait_for(self, condition: Callable[[], bool], timeout: float = WAIT_S) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise AssertionError("the server did not send what was expected in time")
            self.pump(0.05)

    def _read(self, frame: str | bytes) -> None:
        if isinstance(frame, str):
            message = json.loads(frame)
            op = message["op"]
            if op == "serverInfo":
                self.server_info = message
            elif op == "advertise":
                self.channels.update({c["topic"]: c for c in message["channels"]})
            elif op == "unadvertise":
                self.unadvertised += message["channelIds"]
                ids = set(message["channelIds"])
                self.channels = {t: c for t, c in self.channels.items() if c["id"] not in ids}
            elif op == "advertiseServices":
                self.services.update({s["name"]: s for s in message["services"]})
            elif op == "serviceCallFailure":
                self.replies[message["callId"]] = (False, message["message"])
            return
        opcode = frame[0]
        if opcode == 1:  # message data: subscription id, log time, payload
            subscription, log_time = struct.unpack_from("<IQ", frame, 1)
            topic = self._subscriptions.get(subscription)
            if topic is not None:
                self.messages[topic].append(Message(topic, log_time, frame[13:]))
        elif opcode == 2:  # time
            self.times.append(struct.unpack_from("<Q", frame, 1)[0])
        elif opcode == 3:  # service call response
            _, call, length = struct.unpack_from("<III", frame, 1)
            self.replies[call] = (True, frame[13 + length :])
        elif opcode == 4:  # fetch asset response: request id, status, error, data
            request, status, length = struct.unpack_from("<IBI", frame, 1)
            error = frame[10 : 10 + length].decode()
            self.assets[request] = (True, frame[10 + length :]) if status == 0 else (False, error)

    def _id(self) -> int:
        self._next_id += 1
        return self._next_id

    def subscribe(self, *topics: str) -> None:
        subscriptions = []
        for topic in topics:
            subscription = self._id()
            self._subscriptions[subscription] = topic
            subscriptions.append({"id": subscription, "channelId": self.channels[topic]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def unsubscribe(self, *topics: str) -> None:
        ids = [i for i, t in self._subscriptions.items() if t in topics]
        for i in ids:
            del self._subscriptions[i]
        self.ws.send(json.dumps({"op": "unsubscribe", "subscriptionIds": ids}))

    def call(self, service: str, payload: bytes, encoding: str = "json") -> tuple[bool, Any]:
        """Call ``service``; (True, response bytes) or (False, failure message)."""
        call = self._id()
        service_id = self.services[service]["id"]
        head = struct.pack("<BIII", 2, service_id, call, len(encoding)) + encoding.encode()
        self.ws.send(head + payload)
        self.wait_for(lambda: call in self.replies)
        return self.replies.pop(call)

    def fetch(self, uri: str) -> tuple[bool, Any]:
        """Fetch an asset; (True, bytes) or (False, error message)."""
        request = self._id()
        self.ws.send(json.dumps({"op": "fetchAsset", "uri": uri, "requestId": request}))
        self.wait_for(lambda: request in self.assets)
        return self.assets.pop(request)


def validator(channel: dict[str, Any]) -> jsonschema.Draft202012Validator:
    assert channel["encoding"] == "json" and channel["schemaEncoding"] == "jsonschema"
    return jsonschema.Draft202012Validator(json.loads(channel["schema"]))


# -- a world served, stepping in its own thread ------------------------------------------
@dataclass
class Served:
    world: armfleet.World
    server: FoxgloveServer

    def run(self, function: Callable[[], Any]) -> Any:
        """``function()`` in the stepping thread."""
        return self.world.submit(function).result(timeout=WAIT_S)

    def client(self) -> FoxgloveClient:
        return FoxgloveClient.open(self.server.url)


def _step(world: armfleet.World, stop: threading.Event) -> None:
    while not stop.is_set() and not world.closed:
        world.run(0.02, realtime=True)


@pytest.fixture
def served() -> Iterator[Served]:
    """bob at (0, 0) and toby at (1, 0), served on a free port, stepping at the wall clock."""
    world = armfleet.World()
    world.spawn("bob", at=(0, 0))
    world.spawn("toby", at=(1, 0))
    server = world.serve_foxglove(0)
    stop = threading.Event()
    stepper = threading.Thread(target=_step, args=(world, stop), daemon=True)
    stepper.start()
    try:
        yield Served(world, server)
    finally:
        stop.set()
        stepper.join(timeout=10)
        world.close()


# -- topics ------------------------------------------------------------------------------
def test_joint_states_and_tf_arrive_valid_against_their_advertised_schemas(
    served: Served,
) -> None:
    client = served.client()
    info = client.server_info
    assert {"services", "assets", "time"} <= set(info["capabilities"])
    assert info["supportedEncodings"] == ["json"]
    # Every bus topic has its channel, with the recording's schema (same name, same bytes),
    # also those first published after the server started (the arms' status, at 10 Hz).
    client.wait_for(lambda: {"/bob/status", "/toby/status"} <= set(client.channels))
    topics = served.run(lambda: served.world.bus.topics)
    descriptions = {"/bob/robot_description", "/toby/robot_description"}
    assert set(client.channels) == set(topics) | descriptions | {"/scene_objects"}
    for topic, message_type in topics.items():
        schema = encoder_for(message_type).schema
        assert client.channels[topic]["schemaName"] == schema.name, topic
        assert json.loads(client.channels[topic]["schema"]) == json.loads(schema.data), topic
    assert "/bob/robot_description" in client.channels

    client.subscribe("/bob/joint_states", "/tf")
    client.wait_for(
        lambda: all(len(client.messages[t]) >= 50 for t in ("/bob/joint_states", "/tf"))
    )
    now_ns = served.run(lambda: round(served.world.time * 1e9))
    for topic in ("/bob/joint_states", "/tf"):
        check = validator(client.channels[topic])
        received = client.messages[topic]
        for message in received:
            check.validate(message.json)
        times = [m.log_time_ns for m in received]
        assert times == sorted(times) and times[-1] <= now_ns  # simulated time [ns]
    state = client.messages["/bob/joint_states"][-1].json
    assert state["name"][:7] == served.run(lambda: list(served.world.arms["bob"].joint_names))[:7]
    frames = {t["child_frame_id"] for m in client.messages["/tf"] for t in m.json["transforms"]}
    assert {"bob_panda_link7", "toby_panda_link7"} <= frames
    assert client.times and client.times[-1] <= now_ns  # the clock is the simulated one
    client.close()


#: What the SDK answers a client offering only the older subprotocol, as docs/foxglove.md says.
OLD_SUBPROTOCOL_REFUSAL = "Missing expected sec-websocket-protocol header"


def test_an_older_foxglove_websocket_v1_client_is_refused_as_documented(served: Served) -> None:
    """Lichtblick up to 1.21 and clients built on @foxglove/ws-protocol offer only
    foxglove.websocket.v1: the SDK answers HTTP 400 with the body the docs quote; a client
    offering both names (newer Lichtblick) gets foxglove.sdk.v1."""
    with pytest.raises(InvalidStatus) as refused:
        connect(served.server.url, subprotocols=[Subprotocol("foxglove.websocket.v1")], proxy=None)
    response = refused.value.response
    assert response.status_code == 400
    assert bytes(response.body or b"").decode() == OLD_SUBPROTOCOL_REFUSAL
    docs = (Path(__file__).parents[1] / "docs" / "foxglove.md").read_text()
    assert f"HTTP 400 `{OLD_SUBPROTOCOL_REFUSAL}`" in docs
    both = [Subprotocol("foxglove.websocket.v1"), SUBPROTOCOL]
    with connect(served.server.url, subprotocols=both, proxy=None) as accepted:
        assert accepted.subprotocol == SUBPROTOCOL


def test_a_topic_costs_nothing_until_a_client_subscribes(served: Served) -> None:
    bus = served.world.bus
    heard = served.run(lambda: (bus.has_subscribers("/tf"), served.server.listened))
    assert heard == (False, [])  # /tf is not even computed
    client = served.client()
    assert served.run(lambda: served.server.listened) == []  # connected, not subscribed
    client.subscribe("/tf", "/bob/position_controller/state")
    client.wait_for(
        lambda: all(len(client.messages[t]) > 5 for t in ("/tf", "/bob/position_controller/state"))
    )  # computed now (at the display rate: has_subscribers is true at its instants only)
    listened = served.run(lambda: served.server.listened)
    assert listened == ["/bob/position_controller/state", "/tf"]
    client.unsubscribe("/tf")
    client.pump(0.3)
    assert served.run(lambda: served.server.listened) == ["/bob/position_controller/state"]
    client.close()  # leaving unsubscribes from everything
    deadline = time.monotonic() + WAIT_S
    while served.run(lambda: served.server.listened) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert served.run(lambda: (bus.has_subscribers("/tf"), served.server.listened)) == (False, [])


def test_latched_topics_reach_a_client_that_subscribes_later(served: Served) -> None:
    first = served.client()
    first.subscribe("/tf_static", "/bob/robot_description")
    first.wait_for(
        lambda: bool(first.messages["/tf_static"] and first.messages["/bob/robot_description"])
    )
    time.sleep(0.3)  # long after the arms' static transforms were published
    late = served.client()
    late.subscribe("/tf_static", "/bob/robot_description", "/toby/robot_description")
    late.wait_for(
        lambda: all(
            late.messages[t]
            for t in ("/tf_static", "/bob/robot_description", "/toby/robot_description")
        )
    )
    static = {
        t["child_frame_id"] for m in late.messages["/tf_static"] for t in m.json["transforms"]
    }
    assert {"bob_base_link", "toby_base_link"} <= static
    urdf = late.messages["/bob/robot_description"][-1].json["data"]
    validator(late.channels["/bob/robot_description"]).validate({"data": urdf})
    assert "file://" not in urdf and 'filename="/' not in urdf
    assert 'filename="package://panda_description/meshes/visual/link0.dae"' in urdf
    first.close()
    late.close()


def test_arms_spawned_and_removed_while_serving_come_and_go_as_channels(served: Served) -> None:
    client = served.client()
    served.run(lambda: served.world.spawn("carol", at=(2, 0)))
    client.wait_for(lambda: "/carol/joint_states" in client.channels)
    client.wait_for(lambda: "/carol/robot_description" in client.channels)
    client.subscribe("/carol/joint_states")
    client.wait_for(lambda: len(client.messages["/carol/joint_states"]) > 5)
    ok, urdf = client.fetch(urdf_uri("carol"))
    assert ok and b"carol_panda_link7" in urdf
    carol_ids = {c["id"] for t, c in client.channels.items() if t.startswith("/carol/")}
    served.run(lambda: served.world.remove("carol"))
    client.wait_for(lambda: carol_ids <= set(client.unadvertised))
    assert not any(t.startswith("/carol/") for t in client.channels)
    assert "/bob/joint_states" in client.channels
    assert client.fetch(urdf_uri("carol")) == (False, "OSError: not found")
    assert served.run(lambda: served.world.bus.failures) == ()
    client.close()


def test_two_worlds_in_one_process_are_served_apart() -> None:
    with armfleet.World() as one, armfleet.World() as two:
        one.spawn("bob")
        two.spawn("ned")
        first, second = one.serve_foxglove(0), two.serve_foxglove(0)
        assert "/bob/joint_states" in first.topics and "/ned/joint_states" not in first.topics
        assert "/ned/joint_states" in second.topics and "/bob/joint_states" not in second.topics
        client = FoxgloveClient.open(second.url)
        assert not any(t.startswith("/bob/") for t in client.channels)
        client.close()
    assert first.closed and second.closed  # closed with their worlds


def test_a_bad_host_or_port_is_one_clear_error(world: armfleet.World) -> None:
    with pytest.raises(FoxgloveError, match="'nohost' is not an IP address; give one such as"):
        world.serve_foxglove(0, host="nohost")
    with pytest.raises(FoxgloveError, match="port 70000 is invalid"):
        world.serve_foxglove(70000)
    taken = world.serve_foxglove(0)
    with pytest.raises(FoxgloveError, match=f"cannot serve Foxglove on 127.0.0.1:{taken.port}"):
        world.serve_foxglove(taken.port)


# -- assets ------------------------------------------------------------------------------
def test_the_urdf_and_its_meshes_are_served_and_nothing_else(served: Served) -> None:
    client = served.client()
    ok, urdf = client.fetch("package://armfleet/robots/bob.urdf")
    assert ok and urdf.startswith(b"<?xml") and b"package://panda_description/" in urdf
    mesh_uri = "package://panda_description/meshes/visual/link0.dae"
    assert mesh_uri in served.server.asset_uris
    ok, mesh = client.fetch(mesh_uri)
    bob = served.world.arms["bob"]
    link0 = next(
        line.split('"')[1] for line in bob.description.urdf.split() if "visual/link0.dae" in line
    )
    assert ok and mesh == Path(link0).read_bytes()
    mesh_folder = os.path.dirname(os.path.realpath(link0))
    refused = [
        "package://../../etc/passwd",
        "package://armfleet/../../../../etc/passwd",
        "package://panda_description/meshes/visual/../../../../../../etc/passwd",
        "package://panda_description/meshes/visual/link0.dae/../link1.dae",
        "package://panda_description/meshes/visual/%2e%2e/%2e%2e/panda.urdf",
        "package://panda_description/meshes/visual/link0.dae?x",
        "package://unknown_package/meshes/link0.dae",
        "package://armfleet/robots/nobody.urdf",
        "/etc/passwd",
        link0,
        f"file://{link0}",
        f"file://{mesh_folder}/link1.dae",
        "",
    ]
    for uri in refused:
        assert client.fetch(uri) == (False, "OSError: not found"), uri
    client.close()


# -- services ----------------------------------------------------------------------------
def test_the_move_service_moves_bob_to_the_goal(served: Served) -> None:
    client = served.client()
    spec = next(s for s in SERVICE_SCHEMAS if s.name == "/move")
    advertised = client.services["/move"]
    assert advertised["type"] == "armfleet_srvs/srv/Move"
    request_schema = json.loads(advertised["request"]["schema"])
    jsonschema.validate({"name": "bob", "positions": TARGET}, request_schema)
    jsonschema.validate(spec.example, request_schema)
    client.subscribe("/bob/joint_states")
    ok, reply = client.call("/move", json.dumps({"name": "bob", "positions": TARGET}).encode())
    assert ok, reply
    response = json.loads(reply)
    jsonschema.validate(response, json.loads(advertised["response"]["schema"]))
    assert response["moving"] is True and 0 < response["duration_s"] < 5

    def arrived() -> bool:
        received = client.messages["/bob/joint_states"]
        return (
            bool(received)
            and max(abs(q - t) for q, t in zip(received[-1].json["position"], TARGET, strict=False))
            < ARRIVED_RAD
        )

    client.wait_for(arrived)
    positions = served.run(lambda: served.world.arms["bob"].positions)
    assert max(abs(q - t) for q, t in zip(positions, TARGET, strict=True)) < ARRIVED_RAD
    client.close()


def test_grip_move_together_and_reset_services_command_the_world(served: Served) -> None:
    client = served.client()
    home = served.run(lambda: list(served.world.arms["toby"].positions))
    together = {"targets": {"bob": TARGET, "toby": home}}
    ok, reply = client.call("/move_together", json.dumps(together).encode())
    assert ok and json.loads(reply)["arms"] == ["bob", "toby"]
    ok, reply = client.call("/grip", b'{"name": "bob", "action": "width", "width": 0.02}')
    assert ok and json.loads(reply)["target_width"] == pytest.approx(0.02)
    ok, reply = client.call("/reset", b'{"name": "toby"}')
    assert ok and json.loads(reply)["name"] == "toby"
    for spec in SERVICE_SCHEMAS:  # the documented examples are valid requests
        jsonschema.validate(
            spec.example, json.loads(client.services[spec.name]["request"]["schema"])
        )
    client.close()


@pytest.mark.parametrize(
    ("payload", "encoding", "expected"),
    [
        (b'{"name": "bob", "positions": [0.1,', "json", "the request is not valid JSON"),
        (b"\xff\xfe", "json", "the request is not valid JSON"),
        (b'{"name": "bob", "positions": [NaN, 0, 0, 0, 0, 0, 0]}', "json", "NaN is not a JSON"),
        (b'{"name": "ned", "positions": [0, 0, 0, 0, 0, 0, 0]}', "json", "UnknownArm"),
        (b'{"name": "bob", "positons": [0, 0, 0, 0, 0, 0, 0]}', "json", "unknown field 'positons'"),
        (b'{"name": "bob", "positions": "up"}', "json", "'positions' must be a list of numbers"),
        (b'{"name": "bob", "positions": [0, 0]}', "json", "7"),
        (b"[1, 2]", "json", "the request must be a map"),
        (b'{"name": "bob", "positions": [0, 0, 0, 0, 0, 0, 0]}', "cbor", "Unsupported encoding"),
    ],
)
def test_a_malformed_call_gets_an_error_reply_and_the_world_goes_on(
    served: Served, payload: bytes, encoding: str, expected: str
) -> None:
    client = served.client()
    before = served.run(lambda: (served.world.time, list(served.world.arms["bob"].positions)))
    ok, message = client.call("/move", payload, encoding)
    assert not ok and expected in message, message
    assert "Traceback" not in message
    # The world kept stepping, bob did not move, and a valid call still works.
    client.pump(0.1)
    after = served.run(lambda: (served.world.time, list(served.world.arms["bob"].positions)))
    assert after[0] > before[0]
    assert max(abs(a - b) for a, b in zip(after[1], before[1], strict=True)) < 1e-3
    ok, reply = client.call("/reset", b'{"name": "bob", "stop_only": true}')
    assert ok, reply
    assert not any(math.isnan(q) for q in served.run(lambda: served.world.arms["bob"].positions))
    client.close()


def test_a_client_that_never_reads_holds_back_neither_the_world_nor_other_clients() -> None:
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        world.spawn("toby", at=(1, 0))
        world.run(0.2)  # every topic advertised (the arms' status comes at 10 Hz)
        server = world.serve_foxglove(0, rate_hz=None)  # every step: the heaviest stream
        slow = connect(  # its reader stops after one frame: the socket fills, then the queue
            server.url, subprotocols=[SUBPROTOCOL], proxy=None, max_queue=1, close_timeout=0.5,
            legacy=True,
        )  # fmt: skip
        fast = FoxgloveClient.open(server.url)
        advertised: list[dict[str, Any]] = []
        while len(advertised) < len(fast.channels):  # read until every channel is known
            frame = json.loads(slow.recv(timeout=WAIT_S))
            advertised += frame.get("channels", [])
        subscriptions = [{"id": i, "channelId": c["id"]} for i, c in enumerate(advertised)]
        slow.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
        fast.subscribe("/bob/joint_states")
        deadline = time.monotonic() + WAIT_S
        while len(server.listened) < len(world.bus.topics) and time.monotonic() < deadline:
            # Subscribed without stepping: once messages flow, the SDK may leave the rest of
            # a subscribe request of a client that does not read unprocessed.
            world.process_requests()
            time.sleep(0.01)
        assert server.listened == sorted(world.bus.topics)  # every topic
        sent = server.messages_sent
        world.run(3.0)  # flat out: ~6 messages per step to the slow client, never read
        assert server.messages_sent - sent > 3 * 3000  # every one handed over, none waited for
        fast.pump(1.0)
        latest = fast.messages["/bob/joint_states"][-1].log_time_ns
        assert world.time * 1e9 - latest < 0.01e9  # the fast client is not behind
        slow.close()


def test_streams_go_out_at_the_display_rate_one_whole_instant_at_a_time() -> None:
    """At 50 Hz a client gets one instant per 20 ms of simulated time, with both arms'
    /tf of that instant, while the commands and status go out as published; between
    instants the world does not even compute /tf."""
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        world.spawn("toby", at=(1, 0))
        world.run(0.2)
        server = world.serve_foxglove(0, rate_hz=50)
        client = FoxgloveClient.open(server.url)
        client.subscribe("/tf", "/bob/joint_states", "/bob/status")
        deadline = time.monotonic() + WAIT_S
        while len(server.listened) < 3 and time.monotonic() < deadline:
            world.process_requests()
            time.sleep(0.01)
        world.run(1.0)
        client.pump(1.0)
        tf_times = [m.log_time_ns for m in client.messages["/tf"]]
        instants = sorted(set(tf_times))
        assert 49 <= len(instants) <= 51, len(instants)
        assert all(tf_times.count(t) == 2 for t in instants)  # bob's and toby's together
        gaps = {round((b - a) * 1e-9, 6) for a, b in itertools.pairwise(instants)}
        assert gaps == {0.02}, gaps
        states = sorted({m.log_time_ns for m in client.messages["/bob/joint_states"]})
        assert 49 <= len(states) <= 51
        assert len(client.messages["/bob/status"]) >= 9  # 10 Hz, all of them
        # Only the client listens to /tf, so the world computes it at the client's instants:
        # on 5 steps of 100.
        wanted = []
        for _ in range(100):
            wanted.append(world.bus.has_subscribers("/tf"))
            world.step()
        assert sum(wanted) == 5, wanted
        client.close()


def test_serving_from_inside_a_step_or_another_thread_is_refused_and_submit_works() -> None:
    """serve_foxglove subscribes to the bus: like spawn, it is the stepping thread's."""
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        raised: list[BaseException] = []

        def inside(message: object) -> None:
            if not raised:
                try:
                    world.serve_foxglove(0)
                except BaseException as exc:
                    raised.append(exc)

        subscription = world.bus.subscribe("/bob/joint_states", inside)
        world.step()
        subscription.cancel()
        assert len(raised) == 1 and isinstance(raised[0], armfleet.WorldBusy), raised
        with world.step_guard.owned("run"):  # as a loop stepping in this thread would
            elsewhere: list[BaseException] = []
            thread = threading.Thread(
                target=lambda: _capture(elsewhere, lambda: world.serve_foxglove(0))
            )
            thread.start()
            thread.join()
        assert len(elsewhere) == 1 and isinstance(elsewhere[0], armfleet.WorldBusy), elsewhere
        future = world.submit(lambda: world.serve_foxglove(0))
        world.step()
        assert future.result(timeout=1).url.startswith("ws://127.0.0.1:")
        assert not world.bus.failures


def _capture(into: list[BaseException], call: Callable[[], object]) -> None:
    try:
        call()
    except BaseException as exc:
        into.append(exc)


def test_a_bad_rate_is_one_clear_error() -> None:
    with armfleet.World() as world:
        for rate in (0, -5, math.nan, "fast", 1e9):
            with pytest.raises(FoxgloveError, match=r"Foxglove rate .* invalid; give a rate"):
                world.serve_foxglove(0, rate_hz=rate)  # type: ignore[arg-type]


def test_the_documented_layout_names_only_what_the_server_offers(served: Served) -> None:
    """docs/foxglove-layout.json (for bob and toby) cannot drift from the server."""
    layout = json.loads((Path(__file__).parents[1] / "docs" / "foxglove-layout.json").read_text())
    client = served.client()
    client.wait_for(lambda: "/bob/status" in client.channels)
    panels = layout["configById"]
    topics = {
        layer["topic"] for layer in panels["3D!armfleet"]["layers"].values() if "topic" in layer
    }
    topics |= set(panels["3D!armfleet"]["topics"])
    topics |= {path["value"].split(".")[0] for path in panels["Plot!joints"]["paths"]}
    topics.add(panels["RawMessages!tf"]["topicPath"])
    assert topics <= set(client.channels), topics - set(client.channels)
    calls = [config for name, config in panels.items() if name.startswith("CallService!")]
    for call in calls:
        schema = json.loads(client.services[call["serviceName"]]["request"]["schema"])
        jsonschema.validate(json.loads(call["requestPayload"]), schema)
        ok, reply = client.call(call["serviceName"], call["requestPayload"].encode())
        assert ok, reply
    client.close()


def test_import_armfleet_does_not_load_the_foxglove_sdk() -> None:
    code = (
        "import sys, armfleet; print('foxglove' in sys.modules, 'armfleet.foxglove' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]


@pytest.mark.parametrize("name", armfleet.foxglove.__all__)
def test_every_name_of_the_foxglove_package_resolves(name: str) -> None:
    assert getattr(armfleet.foxglove, name) is not None
