"""Issue #28 items 1-4: in a shared world, one client cannot stall or blind the others.

Real processes: a world run by ``armfleet spawn`` and clients on real sockets. One
client's long ``step`` leaves room for the others' requests; a stream answers only to
the client that opened it; quotas bound what one client adds; and an object is not
added into the path of a moving arm.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import msgpack  # type: ignore[import-untyped]
import numpy as np
import pytest
import zmq

import armfleet
from armfleet.errors import ArmfleetError, InvalidNumber
from armfleet.remote import ClientQuotas, RemoteError, serve
from armfleet.services.protocol import PROTOCOL_VERSION
from tests.remote_world import WorldProcess, cli, wait_until

#: Steps of the long request: long enough that another client's requests arrive while
#: it runs, on any machine (several seconds with a Panda in the world).
LONG_STEP_COUNT = 20_000
#: A generous bound for replies on a loaded machine, not a timing requirement [s].
PATIENCE_S = 120.0


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    runtime = tmp_path_factory.mktemp("runtime")
    process = WorldProcess(runtime, "bob", "--at", "0,0", "--no-viewer", "--realtime")
    yield process
    assert process.stop() == 0


def raw_call(socket: zmq.Socket[bytes], op: str, args: dict[str, Any]) -> dict[str, Any]:
    """One request on a raw DEALER socket and its reply."""
    socket.send(msgpack.packb({"id": 1, "op": op, "args": args}))
    assert socket.poll(round(PATIENCE_S * 1000)), f"no reply to {op}"
    reply: dict[str, Any] = msgpack.unpackb(socket.recv())
    return reply


# -- item 1: a long step leaves room for the other clients -------------------------------
def test_another_clients_request_is_answered_while_a_long_step_runs(world: WorldProcess) -> None:
    with (
        armfleet.connect(world.address, timeout=PATIENCE_S) as stepper,
        armfleet.connect(world.address, timeout=PATIENCE_S) as other,
    ):
        start = stepper.pause()
        dt = stepper.info().dt_s
        end = start + LONG_STEP_COUNT * dt
        outcome: list[float] = []
        thread = threading.Thread(target=lambda: outcome.append(stepper.step(LONG_STEP_COUNT)))
        thread.start()
        try:
            # The first answer showing the step under way must come before it ends: a
            # world serving one request at a time answered only once all steps were made.
            seen: list[float] = []

            def under_way() -> bool:
                seen.append(other.info().time_s)
                return seen[-1] > start + dt / 2

            assert wait_until(under_way, timeout=PATIENCE_S, period=0.0)
            first_under_way = seen[-1]
            assert first_under_way < end - dt / 2, (start, first_under_way, end)
            # The other client is served the same while the step goes on; the world stays paused.
            assert other.info().paused
        finally:
            thread.join(timeout=PATIENCE_S)
        # Every step was made, exactly: slices change when others are served, not the steps.
        assert outcome == [pytest.approx(end, abs=dt / 2)]
        assert other.info().time_s == pytest.approx(end, abs=dt / 2)
        stepper.resume()


def test_a_resume_by_another_client_ends_a_long_step_with_one_line(world: WorldProcess) -> None:
    with (
        armfleet.connect(world.address, timeout=PATIENCE_S) as stepper,
        armfleet.connect(world.address, timeout=PATIENCE_S) as other,
    ):
        start = stepper.pause()
        errors: list[BaseException] = []

        def step() -> None:
            try:
                stepper.step(100_000)
            except RemoteError as exc:
                errors.append(exc)

        thread = threading.Thread(target=step)
        thread.start()
        try:
            assert wait_until(lambda: other.info().time_s > start, timeout=PATIENCE_S)
            other.resume()
        finally:
            thread.join(timeout=PATIENCE_S)
        assert len(errors) == 1
        message = str(errors[0])
        assert "\n" not in message
        assert message.startswith("step: another client resumed the world after "), message
        assert "of 100000 steps" in message
        assert not other.info().paused  # the world runs on


# -- item 3: a stream belongs to the client that opened it -------------------------------
def test_another_client_cannot_use_a_streams_token(world: WorldProcess) -> None:
    received: list[object] = []
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    intruder = context.socket(zmq.DEALER)
    intruder.setsockopt(zmq.LINGER, 0)
    intruder.connect(world.address)
    try:
        with armfleet.connect(world.address, timeout=PATIENCE_S) as owner:
            subscription = owner.subscribe("/bob/joint_states", received.append)
            assert wait_until(lambda: len(received) > 0, timeout=PATIENCE_S)
            stream = owner._stream
            assert stream is not None
            token, key = stream.token, subscription._local.key
            attempts: dict[str, dict[str, Any]] = {
                "subscribe": {"stream": token, "topic": "/bob/joint_states", "sub": key + 100},
                "unsubscribe": {"stream": token, "sub": key},
                "detach": {"stream": token},
            }
            for op, args in attempts.items():
                reply = raw_call(intruder, op, args)
                assert not reply["ok"], (op, reply)
                assert reply["error"]["type"] == "StreamNotYours", reply
                message = reply["error"]["message"]
                assert message.startswith(f"{op}: that stream belongs to another client"), message
                assert "\n" not in message
            # The owner's stream and subscription are untouched: messages keep coming.
            count = len(received)
            assert wait_until(lambda: len(received) > count + 10, timeout=PATIENCE_S)
            assert subscription.active
            assert owner.info().subscriptions >= 1
            # The owner itself may unsubscribe.
            subscription.cancel()
            assert not subscription.active
    finally:
        intruder.close()
        context.term()


def test_a_stream_is_its_clients_before_it_holds_any_subscription(world: WorldProcess) -> None:
    """The stream is bound when it attaches, so no other connection can take it first."""
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    sockets = {}
    for name in ("requests", "stream", "intruder"):
        sockets[name] = context.socket(zmq.DEALER)
        sockets[name].setsockopt(zmq.LINGER, 0)
        sockets[name].connect(world.address)
    try:
        hello = raw_call(sockets["requests"], "hello", {"protocol": PROTOCOL_VERSION})
        key = hello["result"]["connection"]
        token = raw_call(sockets["stream"], "attach", {"owner": key})["result"]["stream"]
        subscribe = {"stream": token, "topic": "/bob/joint_states", "sub": 1}
        refused = raw_call(sockets["intruder"], "subscribe", subscribe)
        assert not refused["ok"] and refused["error"]["type"] == "StreamNotYours", refused
        refused = raw_call(sockets["intruder"], "detach", {"stream": token})
        assert not refused["ok"] and refused["error"]["type"] == "StreamNotYours", refused
        # The owner's request connection subscribes; the stream socket receives.
        assert raw_call(sockets["requests"], "subscribe", subscribe)["ok"]
        kinds = set()
        while "messages" not in kinds and sockets["stream"].poll(round(PATIENCE_S * 1000)):
            kinds.add(msgpack.unpackb(sockets["stream"].recv())["kind"])
        assert "messages" in kinds
        # A key that names no connection is refused.
        bogus = raw_call(sockets["intruder"], "attach", {"owner": "0" * 32})
        assert not bogus["ok"] and "'owner' names no connection" in bogus["error"]["message"]
    finally:
        for socket in sockets.values():
            socket.close()
        context.term()


def test_a_stream_socket_still_detaches_itself(world: WorldProcess) -> None:
    with armfleet.connect(world.address, timeout=PATIENCE_S) as client:
        before = client.info().streams
        with armfleet.connect(world.address, timeout=PATIENCE_S) as other:
            other.subscribe("/bob/joint_states", lambda _: None)
            assert wait_until(lambda: client.info().streams == before + 1, timeout=PATIENCE_S)
        # Closing sends detach from the stream socket: the world drops the stream.
        assert wait_until(lambda: client.info().streams == before, timeout=PATIENCE_S)


# -- item 4: an object is not added into the path of another client's moving arm ---------
def test_an_object_in_the_path_of_another_clients_moving_arm_is_refused(
    world: WorldProcess,
) -> None:
    with (
        armfleet.connect(world.address, timeout=PATIENCE_S) as mover,
        armfleet.connect(world.address, timeout=PATIENCE_S) as other,
    ):
        # Paused, so the motion is surely under way when the object is asked for.
        mover.pause()
        try:
            bob = mover.arm("bob")
            home = bob.positions
            hand = mover.lookup("world", "bob_panda_hand")[:3, 3]
            target = home.copy()
            target[0] += 1.2
            bob.move_to(target)
            # The hand's position half-way: its home position turned by 0.6 rad about the
            # first joint's axis, the world's z through bob's base at the origin.
            c, s = np.cos(0.6), np.sin(0.6)
            half_way = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ hand
            with pytest.raises(RemoteError) as refused:
                box = (0.05, 0.05, 0.05)
                other.add_object("crate", "box", size=box, mass=0.0, at=half_way.tolist())
            assert refused.value.kind == "ObjectInArmPath"
            message = str(refused.value)
            assert "\n" not in message
            assert "in the path of arm bob, which is moving" in message, message
            assert "crate" not in other.objects
        finally:
            mover.resume()
        state = bob.wait(timeout=PATIENCE_S)
        assert np.abs(np.asarray(state.position[:7]) - target).max() < 2e-3
        bob.move_to(home)
        bob.wait(timeout=PATIENCE_S)


# -- item 2: the world's owner sets what each client may add -----------------------------
@pytest.fixture(scope="module")
def small_world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    """bob, in a world whose owner allows 2 arms and 1 object per client, 4 arms in all,
    and 3 requests in flight per client."""
    runtime = tmp_path_factory.mktemp("runtime")
    process = WorldProcess(
        runtime, "bob", "--at", "0,0", "--no-viewer", "--realtime",
        "--max-arms-per-client", "2", "--max-world-arms", "4",
        "--max-objects-per-client", "1", "--max-requests-per-client", "3",
    )  # fmt: skip
    yield process
    assert process.stop() == 0


def refusal(call: Any) -> str:
    with pytest.raises(RemoteError) as refused:
        call()
    assert refused.value.kind == "QuotaExceeded", refused.value
    message = str(refused.value)
    assert "\n" not in message
    return message


def test_arm_quotas_per_client_and_for_the_world(small_world: WorldProcess) -> None:
    address = small_world.address
    with armfleet.connect(address, timeout=PATIENCE_S) as first:
        quotas = first.info().quotas
        assert quotas["arms_per_client"] == 2 and quotas["world_arms"] == 4
        first.spawn("ann", at=(2, 0))
        first.spawn("amy", at=(4, 0))
        message = refusal(lambda: first.spawn("ada", at=(6, 0)))
        assert message.startswith(
            "spawn: this client has 2 arms in the world, the arms per client quota (2)"
        ), message
        assert "--max-arms-per-client N" in message
        assert "ClientQuotas(arms_per_client=N)" in message
        assert sorted(first.arms) == ["amy", "ann", "bob"]  # nothing was spawned
        with armfleet.connect(address, timeout=PATIENCE_S) as second:
            second.spawn("ben", at=(6, 0))  # its own quota: the world now holds 4
            message = refusal(lambda: second.spawn("bea", at=(8, 0)))
            assert message.startswith("spawn: the world holds 4 arms, the world arms quota (4)"), (
                message
            )
            assert "--max-world-arms N" in message
            # The command line says it in one line too, and exits with 2.
            joined = cli(small_world.runtime_dir, "spawn", "zed", "--at", "8,8")
            assert joined.returncode == 2, joined
            assert joined.stderr.count("\n") == 1 and "Traceback" not in joined.stderr
            assert "the world arms quota (4)" in joined.stderr
        # A removed arm frees its place, for its client and for the world.
        first.remove("amy")
        first.spawn("ada", at=(4, 0))
        assert sorted(first.arms) == ["ada", "ann", "ben", "bob"]
    # What a client added stays when it leaves, and still counts for the world: a new
    # connection does not get round the world's quota.
    with armfleet.connect(address, timeout=PATIENCE_S) as third:
        assert "world arms quota (4)" in refusal(lambda: third.spawn("cy", at=(8, 0)))
        for name in ("ada", "ann", "ben"):
            third.remove(name)
        assert list(third.arms) == ["bob"]


def test_object_quota_per_client(small_world: WorldProcess) -> None:
    with (
        armfleet.connect(small_world.address, timeout=PATIENCE_S) as first,
        armfleet.connect(small_world.address, timeout=PATIENCE_S) as second,
    ):
        first.add_object("crate", "box", size=(0.1, 0.1, 0.1), at=(2.0, 2.0, 0.05))
        message = refusal(
            lambda: first.add_object("case", "box", size=(0.1, 0.1, 0.1), at=(2.5, 2.0, 0.05))
        )
        assert message.startswith(
            "add_object: this client has 1 object in the world, the objects per client quota (1)"
        ), message
        assert "--max-objects-per-client N" in message
        second.add_object("case", "box", size=(0.1, 0.1, 0.1), at=(2.5, 2.0, 0.05))
        assert sorted(first.objects) == ["case", "crate"]
        first.remove_object("crate")
        second.remove_object("case")


def test_request_quota_per_client_names_the_option(small_world: WorldProcess) -> None:
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    socket = context.socket(zmq.DEALER)
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(small_world.address)
    with armfleet.connect(small_world.address, timeout=PATIENCE_S) as owner:
        owner.pause()  # bob moves but the world does not step: the waits stay in flight
        bob = owner.arm("bob")
        home = bob.positions
        bob.move_to(home + 0.1)
        try:
            for request_id in range(1, 6):
                frame = {"id": request_id, "op": "wait", "args": {"name": "bob"}}
                socket.send(msgpack.packb(frame))
            refused: list[dict[str, Any]] = []
            while len(refused) < 2 and socket.poll(round(PATIENCE_S * 1000)):
                reply = msgpack.unpackb(socket.recv())
                assert not reply["ok"]
                refused.append(reply)
            assert [reply["id"] for reply in refused] == [4, 5]
            for reply in refused:
                assert reply["error"]["type"] == "TooManyRequests"
                message = reply["error"]["message"]
                assert message.startswith(
                    "too many requests in flight from this client (limit 3)"
                ), message
                assert "--max-requests-per-client N" in message
        finally:
            owner.resume()
            socket.close()
            context.term()
        bob.wait(timeout=PATIENCE_S)
        bob.move_to(home)
        bob.wait(timeout=PATIENCE_S)


def test_quota_options_are_refused_by_a_spawn_that_joins(small_world: WorldProcess) -> None:
    joined = cli(small_world.runtime_dir, "spawn", "zed", "--at", "5,5", "--max-world-arms", "9")
    assert joined.returncode == 2
    assert "--max-world-arms set options of a new world" in joined.stderr
    bad = cli(small_world.runtime_dir, "spawn", "zed", "--at", "5,5", "--max-arms-per-client", "-1")
    assert bad.returncode == 2
    assert bad.stderr.count("\n") == 1 and "Traceback" not in bad.stderr
    assert "--max-arms-per-client" in bad.stderr and "0..10000" in bad.stderr


def test_quotas_are_checked_when_the_owner_sets_them() -> None:
    with pytest.raises(InvalidNumber, match="arms_per_client"):
        ClientQuotas(arms_per_client=-1)
    with pytest.raises(InvalidNumber, match="requests_per_client"):
        ClientQuotas(requests_per_client=0)
    with armfleet.World() as world:
        with pytest.raises(ArmfleetError, match=r"quotas must be an armfleet\.remote\."):
            serve(world, register=False, quotas={"arms_per_client": 1})  # type: ignore[arg-type]
        with serve(world, register=False, quotas=ClientQuotas(world_objects=0)) as server:
            assert server.quotas.world_objects == 0


def test_the_fairness_benchmark_writes_every_figure(tmp_path: Path) -> None:
    """Timings are reported, never asserted: the script runs and writes them all."""
    out = tmp_path / "fairness.json"
    script = Path(__file__).resolve().parents[1] / "benchmarks" / "shared_world_fairness.py"
    done = subprocess.run(
        [sys.executable, str(script), "--steps", "3000", "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    figures = json.loads(out.read_text())
    assert figures["steps"] == 3000 and figures["step_request_s"] > 0
    assert figures["info_calls"] >= 1
    assert 0 < figures["info_median_ms"] <= figures["info_max_ms"]
