"""Small things the CLI prints (issue 28, item 25): no negative zero in ``armfleet arms``, and
``armfleet topic echo`` of a silent topic says that it is listening.

Against a live world (``armfleet spawn`` as a subprocess), with the CLI as a subprocess.
"""

from __future__ import annotations

import re
import selectors
import signal
import subprocess
import time
from collections.abc import Iterator

import numpy as np
import pytest

import armfleet
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env

#: A number printed as a negative zero: -0, -0.00, -0.0000 (no other digit).
NEGATIVE_ZERO = re.compile(r"(?<![\d.])-0(?:\.0+)?(?![\d.])")
#: How close an arm at rest holds its target [rad] (its controller's hold tolerance).
HOLD_TOLERANCE_RAD = 1e-3
#: Longest wait for the listening line [s] (a generous bound, not a timing test).
HINT_WAIT_S = 30.0


@pytest.fixture(scope="module")
def bob_world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    """bob turned by -0.4 deg (its yaw prints as 0 to the degree), at home."""
    runtime = tmp_path_factory.mktemp("runtime")
    with WorldProcess(runtime, "bob", "--at", "0,0,0,-0.4", "--no-viewer") as world:
        yield world


def test_arms_prints_no_negative_zero(bob_world: WorldProcess) -> None:
    closed = cli(bob_world.runtime_dir, "grip", "bob", "close", "--wait")
    assert closed.returncode == 0, closed.stderr
    listed = cli(bob_world.runtime_dir, "arms")
    assert listed.returncode == 0, listed.stderr
    _, row, _ = listed.stdout.splitlines()
    assert not NEGATIVE_ZERO.search(listed.stdout), listed.stdout
    assert "0.00, 0.00, 0.00, 0 " in row, row  # the yaw of -0.4 deg, to the degree
    with armfleet.connect(bob_world.address) as client:
        bob = client.arm("bob")
        positions, width = bob.positions, bob.gripper.width
    assert f"{abs(width):.4f} m closed" in row, (row, width)  # a closed gripper: ~0 m
    printed = [float(v) for v in row.rsplit("[", 1)[1].rstrip("]").split()]
    # Rounded to 1e-3, read at another instant: the arm holds within its 1e-3 rad tolerance.
    assert np.abs(np.array(printed) - positions).max() <= 5e-4 + HOLD_TOLERANCE_RAD


def test_echo_of_a_silent_topic_says_it_is_listening(bob_world: WorldProcess) -> None:
    """No contact in the world: /collisions carries nothing; one line on stderr says the
    echo is listening, and stdout stays empty (messages only)."""
    echo = subprocess.Popen(
        [*ARMFLEET, "topic", "echo", "/collisions"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=runtime_env(bob_world.runtime_dir),
    )
    try:
        assert echo.stderr is not None
        with selectors.DefaultSelector() as selector:
            selector.register(echo.stderr, selectors.EVENT_READ)
            deadline = time.monotonic() + HINT_WAIT_S
            while not selector.select(timeout=0.1):
                assert echo.poll() is None, echo.communicate()
                assert time.monotonic() < deadline, "echo said nothing on stderr"
        line = echo.stderr.readline().rstrip("\n")
        assert line == "listening on /collisions; nothing published on it yet (Ctrl-C to stop)"
    finally:
        echo.send_signal(signal.SIGINT)
        out, err = echo.communicate(timeout=HINT_WAIT_S)
    assert out == ""
    assert "Traceback" not in err and "listening" not in err  # said once


def test_echo_of_a_busy_topic_prints_messages_only(bob_world: WorldProcess) -> None:
    echoed = cli(bob_world.runtime_dir, "topic", "echo", "/bob/joint_states", "--timeout", "3")
    assert echoed.returncode == 0, echoed.stderr
    assert echoed.stderr == ""
    assert echoed.stdout.count("---") >= 1


def test_echo_stops_on_ctrl_c_when_started_with_it_ignored(bob_world: WorldProcess) -> None:
    """A shell's background job, or a pytest-xdist worker's child, inherits SIGINT ignored
    (Python then leaves it so): echo, which runs until Ctrl-C, still stops on it."""
    echo = subprocess.Popen(
        [*ARMFLEET, "topic", "echo", "/collisions"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=runtime_env(bob_world.runtime_dir),
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )
    try:
        assert echo.stderr is not None
        line = echo.stderr.readline()  # the listening hint: it has subscribed
        assert line.startswith("listening on /collisions"), line
        echo.send_signal(signal.SIGINT)
        echo.wait(timeout=HINT_WAIT_S)
    finally:
        if echo.poll() is None:
            echo.kill()
            echo.wait()
    assert echo.returncode == 130
