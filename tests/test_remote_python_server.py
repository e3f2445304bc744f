"""Serving a world a Python program steps itself: ``armfleet.remote.serve(world)``."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

import armfleet
from armfleet.remote import RemoteError, WorldServer, serve
from armfleet.remote.server import ServerError
from tests.remote_world import api_threads

HOLD_TOLERANCE_RAD = 2e-3


@dataclass
class Served:
    world: armfleet.World
    server: WorldServer
    stepping: threading.Event

    def step_in_background(self) -> None:
        self.stepping.set()


@pytest.fixture
def served() -> Iterator[Served]:
    """bob in a world stepped by a thread of this process once ``step_in_background()``."""
    world = armfleet.World()
    world.spawn("bob")
    server = serve(world, register=False)
    stepping, stop = threading.Event(), threading.Event()

    def loop() -> None:
        stepping.wait()
        while not stop.is_set():
            world.step()
            # Let the server's and the test's threads take the GIL between steps: stepping
            # flat out, this thread kept it for whole 5 ms switch intervals, and a client
            # call (many handoffs) took seconds and sometimes passed its 5 s timeout.
            time.sleep(0)

    thread = threading.Thread(target=loop)
    thread.start()
    try:
        yield Served(world, server, stepping)
    finally:
        stepping.set()
        stop.set()
        thread.join(timeout=30)
        server.close()
        world.close()
    assert not api_threads()


def test_a_client_moves_an_arm_of_a_python_stepped_world(served: Served) -> None:
    served.step_in_background()
    with armfleet.connect(served.server.address) as client:
        bob = client.arm("bob")
        target = bob.positions + 0.1
        bob.move_to(target)
        bob.wait()
        assert np.abs(served.world.arm("bob").positions - target).max() < HOLD_TOLERANCE_RAD
        # Without a run loop to pause, pausing is refused, not faked.
        with pytest.raises(RemoteError, match="stepped by its own program"):
            client.pause()


def test_a_request_the_world_does_not_take_up_in_time_is_cancelled_not_applied(
    served: Served,
) -> None:
    with armfleet.connect(served.server.address) as client:  # hello needs no stepping
        with pytest.raises(
            RemoteError, match=r"did not take the request up .* nothing was applied"
        ):
            client.call("move", {"name": "bob", "positions": [0.0] * 7}, timeout=0.5)
        served.step_in_background()
        home = np.array(served.world.models.expand("panda", "").home)
        assert np.abs(client.arm("bob").positions - home).max() < HOLD_TOLERANCE_RAD
        assert client.info().time_s > 0


def test_a_port_in_use_is_a_clear_error(served: Served) -> None:
    port = int(served.server.address.rsplit(":", 1)[1])
    with pytest.raises(ServerError, match=f"cannot listen on 127.0.0.1:{port}: .*--api-port"):
        serve(served.world, port=port, register=False)
