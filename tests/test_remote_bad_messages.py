"""Bad messages, one after the other, at a running world: each gets an error reply that
names the problem, and afterwards the world and its arm are untouched and still stepping."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import msgpack  # type: ignore[import-untyped]
import numpy as np
import pytest
import zmq

import armfleet
from armfleet.description import ModelLibrary
from armfleet.services.protocol import MAX_REQUEST_BYTES, PROTOCOL_VERSION
from tests.remote_world import WorldProcess, wait_until

#: How still a holding arm stays between two reads [rad]: its controller's hold tolerance.
UNTOUCHED_RAD = 1e-3
REPLY_TIMEOUT_MS = 10_000

#: How an unknown-model error lists the choices: every model in description/.
AVAILABLE_MODELS = "available: " + ", ".join(ModelLibrary().names)


def request(op: Any, args: Any = None, **extra: Any) -> dict[str, Any]:
    frame: dict[str, Any] = {"id": 1, "op": op, **extra}
    if args is not None:
        frame["args"] = args
    return frame


def one(frame: Any) -> list[bytes]:
    return [msgpack.packb(frame)]


NAN, INF = math.nan, math.inf
HOME = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]


@dataclass(frozen=True)
class Case:
    name: str
    frames: Callable[[str], list[bytes]]  # from the raw socket's stream token
    error: str  # the error type the world names
    says: str  # part of its message


CASES = [
    Case("garbage bytes", lambda t: [b"\xc1\xc1 not msgpack \x00"], "ProtocolError", "msgpack"),
    Case("empty frame", lambda t: [b""], "ProtocolError", "msgpack"),
    Case(
        "trailing bytes", lambda t: [msgpack.packb({"id": 1}) + b"xx"], "ProtocolError", "msgpack"
    ),
    Case("a list, not a map", lambda t: one([1, 2, 3]), "ProtocolError", "must be a map"),
    Case("msgpack ext type", lambda t: one(msgpack.ExtType(5, b"x")), "ProtocolError", "map"),
    Case("two frames", lambda t: one(request("info")) * 2, "ProtocolError", "one frame"),
    Case("missing op", lambda t: one({"id": 1}), "ProtocolError", "missing field 'op'"),
    Case("op not a string", lambda t: one(request(7)), "ProtocolError", "'op' must be a string"),
    Case("id not an integer", lambda t: one({"id": "x", "op": "info"}), "ProtocolError", "'id'"),
    Case(
        "unknown service",
        lambda t: one(request("explode")),
        "UnknownService",
        "services: add_object, arm, arms",
    ),
    Case(
        "unknown request field",
        lambda t: one(request("info", pwn=1)),
        "ProtocolError",
        "unknown field 'pwn'",
    ),
    Case(
        "args not a map", lambda t: one(request("move", [1, 2])), "ProtocolError", "must be a map"
    ),
    Case(
        "unknown argument",
        lambda t: one(request("move", {"name": "bob", "positions": HOME, "speed": 9})),
        "ProtocolError",
        "unknown field 'speed'",
    ),
    Case(
        "missing positions",
        lambda t: one(request("move", {"name": "bob"})),
        "ProtocolError",
        "missing field 'positions'",
    ),
    Case(
        "name of the wrong type",
        lambda t: one(request("move", {"name": 42, "positions": HOME})),
        "ProtocolError",
        "'name' must be a string",
    ),
    Case(
        "positions of the wrong type",
        lambda t: one(request("move", {"name": "bob", "positions": "fast"})),
        "ProtocolError",
        "list of numbers",
    ),
    Case(
        "bools for positions",
        lambda t: one(request("move", {"name": "bob", "positions": [True] * 7})),
        "ProtocolError",
        "a list holding a bool",
    ),
    Case(
        "nested positions",
        lambda t: one(request("move", {"name": "bob", "positions": [HOME]})),
        "ProtocolError",
        "list of numbers",
    ),
    Case(
        "NaN target",
        lambda t: one(request("move", {"name": "bob", "positions": [NAN, *HOME[1:]]})),
        "NonFiniteTarget",
        "bob_panda_joint1 is nan",
    ),
    Case(
        "infinite target",
        lambda t: one(request("move", {"name": "bob", "positions": [*HOME[:6], INF]})),
        "NonFiniteTarget",
        "bob_panda_joint7 is inf",
    ),
    Case(
        "wrong vector length",
        lambda t: one(request("move", {"name": "bob", "positions": [0.0, 0.1, 0.2]})),
        "TargetLengthError",
        "got 3 target positions, expected 7",
    ),
    Case(
        "target outside the joint limits",
        lambda t: one(request("move", {"name": "bob", "positions": [4.0, *HOME[1:]]})),
        "JointLimitError",
        "outside its limits",
    ),
    Case(
        "unknown arm",
        lambda t: one(request("move", {"name": "zed", "positions": HOME})),
        "UnknownArm",
        "no arm named 'zed'; arms: bob",
    ),
    Case(
        "unknown topic",
        lambda t: one(request("subscribe", {"topic": "/zed/joint_states", "stream": t, "sub": 1})),
        "UnknownTopic",
        "unknown topic '/zed/joint_states'; topics: /bob/gripper_controller/commands",
    ),
    Case(
        "malformed topic",
        lambda t: one(request("subscribe", {"topic": "bob states", "stream": t, "sub": 2})),
        "UnknownTopic",
        "topic name 'bob states' is malformed",
    ),
    Case(
        "subscribe on a stream that does not exist",
        lambda t: one(request("subscribe", {"topic": "/bringup", "stream": "nope", "sub": 3})),
        "ProtocolError",
        "no stream 'nope'",
    ),
    Case(
        "publish on a topic the world publishes",
        lambda t: one(
            request("publish", {"topic": "/bob/joint_states", "message": {"positions": HOME}})
        ),
        "ArmfleetError",
        "command topics: /bob/position_controller/commands",
    ),
    Case(
        "oversized payload",
        lambda t: one(request("info", {"pad": "x" * (MAX_REQUEST_BYTES + 1)})),
        "ProtocolError",
        f"exceeds the limit of {MAX_REQUEST_BYTES} bytes",
    ),
    Case(
        "deeply nested payload",
        lambda t: [b"\x91" * 5000 + b"\x00"],
        "ProtocolError",
        "nested too deeply",
    ),
    Case(
        "unknown model",
        lambda t: one(request("spawn", {"name": "carol", "model": "pand", "at": [2, 0]})),
        "UnknownModel",
        AVAILABLE_MODELS,
    ),
    Case(
        "duplicate arm name",
        lambda t: one(request("spawn", {"name": "bob", "at": [2, 0]})),
        "DuplicateArmName",
        "already used",
    ),
    Case(
        "malformed arm name",
        lambda t: one(request("spawn", {"name": "Bob!", "at": [2, 0]})),
        "InvalidArmName",
        "malformed",
    ),
    Case(
        "base inside another arm",
        lambda t: one(request("spawn", {"name": "carol", "at": [0.1, 0]})),
        "StartPoseCollision",
        "carol would touch bob at its start pose",
    ),
    Case(
        "NaN spawn pose",
        lambda t: one(request("spawn", {"name": "carol", "at": {"x": NAN, "y": 2}})),
        "PoseError",
        "x is nan",
    ),
    Case(
        "spawn pose of the wrong length",
        lambda t: one(request("spawn", {"name": "carol", "at": [1, 2, 3, 4, 5]})),
        "PoseError",
        "(x, y[, z[, yaw_deg]])",
    ),
    Case(
        "controller parameter out of bounds",
        lambda t: one(
            request(
                "spawn",
                {
                    "name": "carol",
                    "at": [2, 0],
                    "parameters": {"position_controller": {"kp_s2": -1}},
                },
            )
        ),
        "ParameterError",
        "kp_s2",
    ),
    Case(
        "protocol version mismatch",
        lambda t: one(request("hello", {"protocol": PROTOCOL_VERSION + 1})),
        "ProtocolError",
        "use the same armfleet version",
    ),
    Case(
        "negative timeout",
        lambda t: one(request("info", timeout_s=-1)),
        "ProtocolError",
        "'timeout_s' is -1",
    ),
    Case(
        "step while running",
        lambda t: one(request("step", {"count": 10})),
        "ArmfleetError",
        "pause it first",
    ),
    Case(
        "step count of zero",
        lambda t: one(request("step", {"count": 0})),
        "ProtocolError",
        "'count' is 0",
    ),
]


@dataclass
class Target:
    world: WorldProcess
    client: armfleet.remote.Client
    socket: zmq.Socket[bytes]
    token: str
    home: np.ndarray
    topics: set[str]


@pytest.fixture(scope="module")
def target(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Target]:
    runtime = tmp_path_factory.mktemp("runtime")
    world = WorldProcess(runtime, "bob", "--at", "0,0", "--no-viewer", "--realtime")
    context = zmq.Context()
    raw = context.socket(zmq.DEALER)
    raw.setsockopt(zmq.LINGER, 0)
    raw.connect(world.address)
    try:
        with armfleet.connect(world.address) as client:
            # Past the first periodic reports, so that every topic is advertised.
            assert wait_until(lambda: client.info().time_s > 0.3)
            token = exchange(raw, [msgpack.packb(request("attach"))])["result"]["stream"]
            yield Target(
                world, client, raw, token, client.arm("bob").positions, set(client.topics())
            )
    finally:
        raw.close()
        context.term()
        assert world.stop() == 0


def exchange(socket: zmq.Socket[bytes], frames: list[bytes]) -> dict[str, Any]:
    """Send ``frames`` and return the reply, past the ticks the server sends every
    second (of wall time) to a connection that opened a stream, as any client must."""
    socket.send_multipart(frames)
    while True:
        assert socket.poll(REPLY_TIMEOUT_MS), "no reply"
        reply: dict[str, Any] = msgpack.unpackb(socket.recv())
        if reply.get("kind") != "tick":
            return reply


@pytest.mark.parametrize("case", CASES, ids=[case.name for case in CASES])
def test_bad_message_gets_an_error_and_leaves_the_world_untouched(
    target: Target, case: Case
) -> None:
    before = target.client.info().time_s
    reply = exchange(target.socket, case.frames(target.token))
    assert reply["kind"] == "reply" and reply["ok"] is False, reply
    assert reply["error"]["type"] == case.error, reply["error"]
    assert case.says in reply["error"]["message"], reply["error"]["message"]
    assert "\n" not in reply["error"]["message"]  # one line, as the CLI shows it
    # Untouched: same arms, same topics, bob where it was, and the world still steps.
    client = target.client
    assert client.info().arms == ("bob",)
    assert set(client.topics()) == target.topics
    assert np.abs(client.arm("bob").positions - target.home).max() < UNTOUCHED_RAD
    assert client.info().time_s > before


def test_a_frame_past_the_hard_limit_drops_only_that_connection(target: Target) -> None:
    context = zmq.Context()
    flooder = context.socket(zmq.DEALER)
    flooder.setsockopt(zmq.LINGER, 0)
    flooder.connect(target.world.address)
    try:
        flooder.send(b"\x00" * (17 * 1024 * 1024))
        assert not flooder.poll(500)  # no reply: ZeroMQ cut the connection
    finally:
        flooder.close()
        context.term()
    before = target.client.info().time_s
    assert np.abs(target.client.arm("bob").positions - target.home).max() < UNTOUCHED_RAD
    assert target.client.info().time_s > before
