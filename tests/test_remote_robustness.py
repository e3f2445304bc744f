"""Clients that misbehave — stuck, slow, vanished — never hold the world up; the API is
not reachable from other machines unless asked for."""

from __future__ import annotations

import itertools
import json
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import armfleet
from armfleet.messages import JointState
from tests.remote_world import WorldProcess, api_threads, runtime_file, wait_until, world_times

#: A client process that subscribes to bob's joint states and /tf, then sleeps.
SUBSCRIBER = """
import sys, time, armfleet
client = armfleet.connect(sys.argv[1])
client.subscribe("/bob/joint_states", lambda message: None)
client.subscribe("/tf", lambda message: None)
print("subscribed", flush=True)
time.sleep(600)
"""


@pytest.fixture
def world(tmp_path: Path) -> Iterator[WorldProcess]:
    # Paced to the wall clock: a flat-out world starved the client and server threads
    # of CPU on the 2-core CI machine (a 5 s request timeout ran out once in three runs).
    process = WorldProcess(tmp_path, "bob", "--at", "0,0", "--no-viewer", "--realtime")
    yield process
    assert process.stop() == 0
    assert not api_threads()


def strictly_increasing(values: list[float]) -> bool:
    return all(later > earlier for earlier, later in itertools.pairwise(values))


def test_a_stuck_subscriber_does_not_hold_the_world_and_then_gets_fresh_messages(
    world: WorldProcess,
) -> None:
    release = threading.Event()
    received: list[JointState] = []

    def stuck(state: JointState) -> None:
        release.wait(timeout=30)  # the first call blocks, like a client that hangs
        received.append(state)

    with armfleet.connect(world.address) as client:
        subscription = client.subscribe("/bob/joint_states", stuck, queue_size=50)
        assert wait_until(lambda: client.info().subscriptions == 1)
        times = world_times(client, count=15, period=0.1)
        assert strictly_increasing(times)  # the world kept stepping while the callback hung
        release.set()
        now = client.info().time_s
        # Fresh messages arrive soon after, not a replay of everything it missed ...
        assert wait_until(lambda: bool(received) and received[-1].stamp >= now, timeout=10)
        # ... because the oldest were dropped, and counted.
        assert subscription.dropped > 0
        # Of the states stamped before the release (one per 1 ms step since the hang began),
        # fewer than half came through; the fresh ones after it keep flowing meanwhile, as
        # many as the machine delivers before the wait above sees one, so they don't count.
        missed = [state for state in received if state.stamp < now]
        assert len(missed) < (now - times[0]) / 0.001 / 2
        subscription.cancel()
        assert wait_until(lambda: client.info().subscriptions == 0)


def test_a_rate_limited_subscription_never_exceeds_its_rate(world: WorldProcess) -> None:
    stamps: list[float] = []
    with armfleet.connect(world.address) as client:
        subscription = client.subscribe("/bob/joint_states", lambda s: stamps.append(s.stamp), 20)
        time.sleep(1.0)
        subscription.cancel()
        count = len(stamps)
    # The world publishes 1 kHz of simulated time, several times faster than the wall
    # clock here; the subscriber gets at most 20 a second, however fast the machine.
    assert 1 <= count <= 20 * 1.0 + 2
    assert subscription.dropped == 0


def test_a_frozen_then_killed_client_process_is_dropped_and_the_world_goes_on(
    world: WorldProcess,
) -> None:
    child = subprocess.Popen(
        [sys.executable, "-c", SUBSCRIBER, world.address], stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout is not None and child.stdout.readline().strip() == "subscribed"
        with armfleet.connect(world.address) as client:
            assert client.info().subscriptions == 2
            child.send_signal(signal.SIGSTOP)  # alive but reading nothing
            # Still connected (its queues drop the oldest) until the server's silent-peer
            # check drops it after a few seconds; on a loaded machine that can come soon.
            assert client.info().streams == 1
            assert strictly_increasing(world_times(client, count=10, period=0.1))
            child.send_signal(signal.SIGKILL)  # gone mid-stream
            child.wait(timeout=10)
            assert wait_until(lambda: client.info().streams == 0, timeout=15)
            assert client.info().subscriptions == 0
            assert strictly_increasing(world_times(client, count=5, period=0.05))
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def machine_address() -> str | None:
    """A non-loopback IPv4 address of this machine (read from ``ip``; nothing is sent)."""
    try:
        listing = subprocess.run(
            ["ip", "-j", "-4", "addr"], capture_output=True, text=True, timeout=10, check=True
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    for interface in json.loads(listing or "[]"):
        for address in interface.get("addr_info", []):
            if not address.get("local", "127.").startswith("127."):
                return str(address["local"])
    return None


def refused(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=5):
            return False
    except ConnectionRefusedError:
        return True


@pytest.fixture
def lan_address() -> str:
    address = machine_address()
    if address is None:
        pytest.skip("this machine has no non-loopback IPv4 address")
    return address


def test_the_api_does_not_answer_on_other_addresses_by_default(
    tmp_path: Path, lan_address: str
) -> None:
    with WorldProcess(tmp_path, "bob", "--at", "0,0", "--no-viewer") as world:
        assert world.address.startswith("tcp://127.0.0.1:")
        port = int(world.address.rsplit(":", 1)[1])
        assert refused(lan_address, port)
        with pytest.raises(armfleet.remote.NoWorldFound, match="no answer"):
            armfleet.connect(f"tcp://{lan_address}:{port}", timeout=0.5)
        assert not any("warning" in line for line in world.stderr)
        with armfleet.connect(world.address) as client:
            assert client.info().arms == ("bob",)


def test_the_api_answers_on_another_address_only_when_told_and_warns(
    tmp_path: Path, lan_address: str
) -> None:
    with WorldProcess(
        tmp_path, "bob", "--at", "0,0", "--no-viewer", "--api-bind", lan_address
    ) as world:
        assert world.address.startswith(f"tcp://{lan_address}:")
        with armfleet.connect(world.address) as client:
            assert client.info().arms == ("bob",)
        port = int(world.address.rsplit(":", 1)[1])
        assert refused("127.0.0.1", port)  # bound to that address only
        assert json.loads(runtime_file(tmp_path).read_text())["address"] == world.address
        assert wait_until(lambda: any("warning" in line for line in world.stderr))
        warning = next(line for line in world.stderr if "warning" in line)
        assert "anyone who can reach this machine" in warning
