"""Issue #14 item 3: one live-API client cannot lock out the others.

Real sockets against a world in another process. Limits are per client: a client
over its own limit gets a "too many requests in flight from this client" reply
per request, never silence, while the others are served; every request of a
burst gets exactly one reply; and the requests of a client that disconnects are
cancelled at once, freeing the world for everyone else.
"""

from __future__ import annotations

import collections
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any

import msgpack  # type: ignore[import-untyped]
import numpy as np
import pytest
import zmq

import armfleet
from armfleet.services.protocol import MAX_IN_FLIGHT_PER_CLIENT
from tests.remote_world import WorldProcess, wait_until

#: Longest a test waits for replies before calling them missing [s]: a generous bound
#: for a loaded 2-core machine, not a timing requirement.
PATIENCE_S = 120.0
OVER_LIMIT = f"too many requests in flight from this client (limit {MAX_IN_FLIGHT_PER_CLIENT})"


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    runtime = tmp_path_factory.mktemp("runtime")
    process = WorldProcess(runtime, "bob", "--at", "0,0", "--no-viewer", "--realtime")
    yield process
    assert process.stop() == 0


def raw_socket(context: zmq.Context[zmq.Socket[bytes]], address: str) -> zmq.Socket[bytes]:
    socket = context.socket(zmq.DEALER)
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(address)
    return socket


def request(request_id: int, op: str, args: dict[str, Any] | None = None) -> bytes:
    frame = {"id": request_id, "op": op, "args": args or {}}
    return bytes(msgpack.packb(frame))


def collect(socket: zmq.Socket[bytes], count: int) -> list[dict[str, Any]]:
    """Read replies until ``count`` came or none came for PATIENCE_S."""
    replies: list[dict[str, Any]] = []
    while len(replies) < count and socket.poll(round(PATIENCE_S * 1000)):
        replies.append(msgpack.unpackb(socket.recv()))
    return replies


def check_one_reply_each(replies: list[dict[str, Any]], count: int) -> collections.Counter[str]:
    """Every id 1..count answered exactly once; returns the outcomes by kind."""
    ids = collections.Counter(r["id"] for r in replies)
    assert sorted(ids) == list(range(1, count + 1)), f"{count - len(ids)} requests unanswered"
    assert max(ids.values()) == 1, "a request answered twice"
    outcomes: collections.Counter[str] = collections.Counter()
    for reply in replies:
        if reply["ok"]:
            outcomes["ok"] += 1
        else:
            assert reply["error"]["type"] == "TooManyRequests", reply
            assert reply["error"]["message"].startswith(OVER_LIMIT), reply
            outcomes["refused"] += 1
    return outcomes


def test_a_flooding_client_does_not_lock_out_a_well_behaved_one(world: WorldProcess) -> None:
    flood = 4000
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    flooder = raw_socket(context, world.address)
    flooding = threading.Event()
    replies: list[dict[str, Any]] = []

    def run_flood() -> None:  # sends everything before it reads anything
        for request_id in range(1, flood + 1):
            flooder.send(request(request_id, "info"))
            if request_id == MAX_IN_FLIGHT_PER_CLIENT:
                flooding.set()
        replies.extend(collect(flooder, flood))

    thread = threading.Thread(target=run_flood)
    thread.start()
    latencies = []
    try:
        assert flooding.wait(PATIENCE_S)
        with armfleet.connect(world.address, timeout=PATIENCE_S) as client:
            for _ in range(20):  # while the flood is on
                started = time.monotonic()
                assert client.info().arms == ("bob",)  # answered, not refused
                latencies.append(time.monotonic() - started)
    finally:
        thread.join(PATIENCE_S)
        flooder.close()
        context.term()
    outcomes = check_one_reply_each(replies, flood)
    assert outcomes["refused"] > 0  # the flooder met its own limit
    print(f"well-behaved client during the flood: median {np.median(latencies) * 1e3:.1f} ms, "
          f"max {max(latencies) * 1e3:.1f} ms; flooder: {dict(outcomes)}")  # fmt: skip


def test_a_burst_of_10000_requests_gets_exactly_one_reply_each(world: WorldProcess) -> None:
    burst = 10_000
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    socket = raw_socket(context, world.address)
    try:
        for request_id in range(1, burst + 1):
            socket.send(request(request_id, "info"))
        replies = collect(socket, burst)
        assert not socket.poll(200)  # and nothing more
    finally:
        socket.close()
        context.term()
    outcomes = check_one_reply_each(replies, burst)
    assert outcomes["ok"] >= MAX_IN_FLIGHT_PER_CLIENT


VANISHING_CLIENT = """
import sys, msgpack, zmq
address, waits = sys.argv[1], int(sys.argv[2])
socket = zmq.Context().socket(zmq.DEALER)
socket.connect(address)
for i in range(1, waits + 1):
    socket.send(msgpack.packb({"id": i, "op": "wait", "args": {"name": "bob", "timeout_s": 600}}))
refused = 0  # the waits past its limit are refused at once; the rest stay pending
while refused < waits - int(sys.argv[3]) and socket.poll(30_000):
    socket.recv()
    refused += 1
print("waiting", flush=True)
sys.stdin.read()  # until killed
"""


def test_the_waits_of_a_client_that_vanishes_are_cancelled_and_others_served_at_once(
    world: WorldProcess,
) -> None:
    waits = 256
    with armfleet.connect(world.address, timeout=PATIENCE_S) as client:
        bob = client.arm("bob")
        home = bob.positions
        # bob mid-motion in a paused world: a wait for him stays pending until cancelled.
        bob.move_to(home + 0.5 * np.array([1, -1, 1, 1, 1, -1, 1]))
        client.pause()
        vanishing = subprocess.Popen(
            [sys.executable, "-c", VANISHING_CLIENT, world.address, str(waits),
             str(MAX_IN_FLIGHT_PER_CLIENT)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            assert vanishing.stdout is not None
            assert vanishing.stdout.readline().strip() == "waiting"
            assert client.info().paused  # others are served meanwhile
            # Its own limit held it: the rest of the world is not full.
            assert client.call("info")["requests"] == MAX_IN_FLIGHT_PER_CLIENT
        finally:
            vanishing.kill()
            vanishing.wait()
        # Gone: its waits are cancelled (they no longer count) and everyone is served.
        assert wait_until(lambda: client.call("info")["requests"] == 0, timeout=PATIENCE_S)
        assert client.arm("bob").name == "bob"
        client.resume()
        state = bob.wait(timeout=PATIENCE_S)
        assert state is not None
        bob.move_to(home)
        bob.wait(timeout=PATIENCE_S)
