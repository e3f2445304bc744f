"""Bad live-API wire input beyond tests/test_remote_bad_messages.py: each class gets
exactly one error reply naming the problem, and the world, its arm and the other
clients are untouched.

The catalogue here covers the request envelope (ids, timeouts), streams and
subscriptions, waits, the options of collision-free moves, and a client over its own
in-flight limit.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import msgpack  # type: ignore[import-untyped]
import numpy as np
import pytest
import zmq

import armfleet
from armfleet.services.protocol import MAX_IN_FLIGHT_PER_CLIENT, MAX_QUEUE_SIZE
from tests.remote_world import WorldProcess, wait_until

#: How still a holding arm stays between two reads [rad]: its controller's hold tolerance.
UNTOUCHED_RAD = 1e-3
#: Longest wait for a reply before calling it missing [ms]: generous, not a timing test.
REPLY_TIMEOUT_MS = 30_000
NAN, INF = math.nan, math.inf


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
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    raw = context.socket(zmq.DEALER)
    raw.setsockopt(zmq.LINGER, 0)
    raw.connect(world.address)
    try:
        with armfleet.connect(world.address) as client:
            assert wait_until(lambda: client.info().time_s > 0.3)  # every topic advertised
            token = exchange(raw, [{"id": 1, "op": "attach"}])[0]["result"]["stream"]
            subscribed = exchange(
                raw,
                [{"id": 2, "op": "subscribe", "args": {"topic": "/bob/status", "stream": token,
                                                        "sub": 7, "rate_hz": 1.0}}],
            )[0]  # fmt: skip
            assert subscribed["ok"], subscribed
            yield Target(
                world, client, raw, token, client.arm("bob").positions, set(client.topics())
            )
    finally:
        raw.close()
        context.term()
        assert world.stop() == 0


def exchange(socket: zmq.Socket[bytes], requests: list[Any]) -> list[dict[str, Any]]:
    """Send each request (a frame each), return one reply per request (in any order)."""
    for frame in requests:
        socket.send(frame if isinstance(frame, bytes) else msgpack.packb(frame))
    replies: list[dict[str, Any]] = []
    while len(replies) < len(requests):
        assert socket.poll(REPLY_TIMEOUT_MS), f"{len(requests) - len(replies)} replies missing"
        reply = msgpack.unpackb(socket.recv())
        if reply.get("kind") == "reply":  # the raw stream's topic frames come here too
            replies.append(reply)
    return replies


#: Bob's home with joint 1 turned 0.5 rad: a move that got through ends far from home.
AWAY = [0.5, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
#: Bob's tool 3 cm into the floor, joint limits kept: a goal in collision.
IN_THE_FLOOR = [0.0, 1.7, 0.0, -0.8, 0.0, 3.5, 0.785]


def planned(**args: Any) -> dict[str, Any]:
    """The args of a collision-free move of bob to :data:`AWAY`, with ``args`` over them."""
    return {"name": "bob", "positions": AWAY, "avoid_collisions": True} | args


def req(op: str, args: Any = None, request_id: Any = 1, **extra: Any) -> dict[str, Any]:
    frame: dict[str, Any] = {"id": request_id, "op": op, **extra}
    if args is not None:
        frame["args"] = args
    return frame


def sub(token: str, **args: Any) -> dict[str, Any]:
    return req("subscribe", {"topic": "/bob/joint_states", "stream": token, "sub": 99} | args)


CASES = [
    pytest.param(
        lambda t: [req("info", request_id=-1)],
        "ProtocolError",
        "'id'",
        id="negative request id -> ProtocolError naming 'id'",
    ),
    pytest.param(
        lambda t: [req("info", request_id=2**64 - 1)],
        "ProtocolError",
        "'id'",
        id="request id past int64 -> ProtocolError naming 'id'",
    ),
    pytest.param(
        lambda t: [req("info", request_id=True)],
        "ProtocolError",
        "'id'",
        id="bool request id -> ProtocolError naming 'id'",
    ),
    pytest.param(
        lambda t: [{"op": "info"}],
        "ProtocolError",
        "missing field 'id'",
        id="no request id -> ProtocolError, missing field 'id'",
    ),
    pytest.param(
        lambda t: [req("info", timeout_s=NAN)],
        "ProtocolError",
        "'timeout_s'",
        id="NaN timeout -> ProtocolError naming 'timeout_s'",
    ),
    pytest.param(
        lambda t: [req("info", timeout_s=INF)],
        "ProtocolError",
        "'timeout_s'",
        id="infinite timeout -> ProtocolError naming 'timeout_s'",
    ),
    pytest.param(
        lambda t: [req("info", timeout_s="soon")],
        "ProtocolError",
        "'timeout_s'",
        id="timeout as text -> ProtocolError naming 'timeout_s'",
    ),
    pytest.param(
        lambda t: [req("")],
        "UnknownService",
        "services: add_object",
        id="empty op -> UnknownService listing the services",
    ),
    pytest.param(
        lambda t: [{1: 2, "id": 1, "op": "info"}],
        "ProtocolError",
        "not allowed for map key",
        id="map with a non-text key -> ProtocolError naming the map key",
    ),
    pytest.param(
        lambda t: [sub(t, sub=7)],
        "ProtocolError",
        "subscription 7 exists already",
        id="subscription key used twice on a stream -> ProtocolError, exists already",
    ),
    pytest.param(
        lambda t: [sub(t, queue_size=0)],
        "ProtocolError",
        "'queue_size'",
        id="queue size 0 -> ProtocolError naming 'queue_size'",
    ),
    pytest.param(
        lambda t: [sub(t, queue_size=MAX_QUEUE_SIZE + 1)],
        "ProtocolError",
        "'queue_size'",
        id="queue size past the maximum -> ProtocolError naming 'queue_size'",
    ),
    pytest.param(
        lambda t: [sub(t, rate_hz=-1.0)],
        "ProtocolError",
        "'rate_hz'",
        id="negative rate -> ProtocolError naming 'rate_hz'",
    ),
    pytest.param(
        lambda t: [sub(t, rate_hz=NAN)],
        "ProtocolError",
        "'rate_hz'",
        id="NaN rate -> ProtocolError naming 'rate_hz'",
    ),
    pytest.param(
        lambda t: [sub(t, sub=-3)],
        "ProtocolError",
        "'sub'",
        id="negative subscription key -> ProtocolError naming 'sub'",
    ),
    pytest.param(
        lambda t: [req("unsubscribe", {"stream": "nope", "sub": 7})],
        "ProtocolError",
        "no stream 'nope'",
        id="unsubscribe on a stream that does not exist -> ProtocolError, no stream",
    ),
    pytest.param(
        lambda t: [req("wait", {"name": "zed"})],
        "UnknownArm",
        "no arm named 'zed'; arms: bob",
        id="wait for an unknown arm -> UnknownArm listing the arms",
    ),
    pytest.param(
        lambda t: [req("wait", {"name": "bob", "timeout_s": -1})],
        "ProtocolError",
        "'timeout_s'",
        id="wait with a negative timeout -> ProtocolError naming 'timeout_s'",
    ),
    pytest.param(
        lambda t: [req("wait", {"name": "bob", "timeout_s": NAN})],
        "ProtocolError",
        "'timeout_s'",
        id="wait with a NaN timeout -> ProtocolError naming 'timeout_s'",
    ),
    # -- collision-free moves (issue 16): the flag and the planner's ranges ----------------
    pytest.param(
        lambda t: [req("move", {"name": "bob", "positions": AWAY, "avoid_collisions": "yes"})],
        "ProtocolError",
        "move: 'avoid_collisions' must be true or false, got a string",
        id="move with avoid_collisions 'yes' -> ProtocolError (not read as yes)",
    ),
    pytest.param(
        lambda t: [req("move_together", {"targets": {"bob": AWAY}, "avoid_collisions": 1})],
        "ProtocolError",
        "move_together: 'avoid_collisions' must be true or false",
        id="move_together with avoid_collisions 1 -> ProtocolError",
    ),
    pytest.param(
        lambda t: [req("move", planned(clearance_m=0))],
        "ProtocolError",
        "move: 'clearance_m' is 0; give metres in [0.001, 0.5]",
        id="planned move with clearance 0 -> ProtocolError with the range",
    ),
    pytest.param(
        lambda t: [req("move", planned(clearance_m=NAN))],
        "ProtocolError",
        "move: 'clearance_m' is nan; give metres in [0.001, 0.5]",
        id="planned move with a NaN clearance -> ProtocolError with the range",
    ),
    pytest.param(
        lambda t: [
            req(
                "move_pose",
                {
                    "name": "bob",
                    "position": [0.4, 0.0, 0.5],
                    "avoid_collisions": True,
                    "timeout_s": -1,
                },
            )
        ],
        "ProtocolError",
        "move_pose: 'timeout_s' is -1; give seconds in [0.001, 60]",
        id="planned move_pose with a negative budget -> ProtocolError with the range",
    ),
    pytest.param(
        lambda t: [req("move", planned(budget=0))],
        "ProtocolError",
        "move: 'budget' is 0; give planner iterations, an integer in 1..1000000",
        id="planned move with a budget of 0 -> ProtocolError with the range",
    ),
    pytest.param(
        lambda t: [req("move", planned(budget=100, timeout_s=1.0))],
        "ProtocolError",
        "move: give 'timeout_s' (wall time) or 'budget' (planner iterations), not both",
        id="planned move with a budget and a timeout -> ProtocolError, one or the other",
    ),
    pytest.param(
        lambda t: [req("move", {"name": "bob", "positions": AWAY, "budget": 100})],
        "ProtocolError",
        "move: 'budget' goes with 'avoid_collisions': true",
        id="budget without avoid_collisions -> ProtocolError (not a straight move)",
    ),
    pytest.param(
        lambda t: [req("move", {"name": "bob", "positions": AWAY, "clearance_m": 0.05})],
        "ProtocolError",
        "move: 'clearance_m' goes with 'avoid_collisions': true",
        id="clearance without avoid_collisions -> ProtocolError (not a straight move)",
    ),
    pytest.param(
        lambda t: [
            req(
                "move_pose",
                {
                    "name": "bob",
                    "position": [0.4, 0.0, 0.5],
                    "linear": True,
                    "avoid_collisions": True,
                },
            )
        ],
        "ArmfleetError",
        "bob: choose linear=True (a straight tool line) or avoid_collisions=True",
        id="move_pose linear and avoid_collisions -> the arm's one line, nothing moves",
    ),
    pytest.param(
        lambda t: [req("move", planned(positions=IN_THE_FLOOR))],
        "PlanningFailed",
        "cannot plan bob: goal in collision: bob_panda_",
        id="planned move to a goal in the floor -> PlanningFailed naming the pair, no motion",
    ),
    pytest.param(
        lambda t: [req("info", request_id=i) for i in range(1, 3 * MAX_IN_FLIGHT_PER_CLIENT)],
        "TooManyRequests",
        f"too many requests in flight from this client (limit {MAX_IN_FLIGHT_PER_CLIENT})",
        id="more requests in flight than a client may have -> TooManyRequests for each extra "
        "one, one reply per request",
    ),
]


@pytest.mark.parametrize(("frames", "error", "says"), CASES)
def test_bad_live_api_input_gets_one_error_reply_and_leaves_the_world_untouched(
    target: Target, frames: Any, error: str, says: str
) -> None:
    before = target.client.info().time_s
    requests = frames(target.token)
    replies = exchange(target.socket, requests)
    refused = [r for r in replies if not r["ok"]]
    assert refused, replies
    for reply in refused:
        assert reply["error"]["type"] == error, reply["error"]
        assert says in reply["error"]["message"], reply["error"]["message"]
        assert "\n" not in reply["error"]["message"]  # one line, as the CLI shows it
    assert not target.socket.poll(100) or _only_topic_frames(target.socket)  # nothing more
    client = target.client
    assert client.info().arms == ("bob",)
    assert set(client.topics()) == target.topics
    assert np.abs(client.arm("bob").positions - target.home).max() < UNTOUCHED_RAD
    assert client.info().time_s > before


def _only_topic_frames(socket: zmq.Socket[bytes]) -> bool:
    while socket.poll(100):
        if msgpack.unpackb(socket.recv()).get("kind") == "reply":
            return False
    return True
