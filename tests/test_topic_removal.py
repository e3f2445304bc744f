"""Issue #14 item 10: a removed arm's topics go, their subscribers are told, and
``topic echo --timeout T`` always ends.

In process: ``World.remove`` withdraws ``/<arm>/*`` from the bus and calls each
subscriber's ``on_gone``. Live: ``topic list`` no longer shows them, an ``echo``
of one ends with one line naming the topic and exit 2, and ``--timeout`` ends the
command whatever the world does (silent topic, hung world).
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from collections.abc import Iterator

import pytest

import armfleet
from armfleet.messages import JointState
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env

#: Longest a CLI command may take before the test calls it hung [s]: a generous bound
#: (a slow machine's Python start-up is seconds); the commands under test used to hang forever.
HUNG_S = 60.0
#: The --timeout given to echo [s].
ECHO_TIMEOUT_S = 2.0


def ned_topics(topics: object) -> list[str]:
    return sorted(t for t in topics if t.startswith("/ned/"))  # type: ignore[attr-defined]


# -- in process ----------------------------------------------------------------------------
def test_removing_an_arm_withdraws_its_topics_and_tells_their_subscribers(
    world: armfleet.World,
) -> None:
    world.spawn("bob")
    world.spawn("ned", at=(1, 0))
    world.step()
    before = ned_topics(world.bus.topics)
    assert "/ned/joint_states" in before
    told: list[tuple[str, str]] = []
    states: list[JointState] = []
    world.bus.subscribe(
        "/ned/joint_states", states.append, on_gone=lambda t, why: told.append((t, why))
    )
    world.bus.subscribe("/ned/status", lambda _: None, on_gone=lambda t, why: told.append((t, why)))
    bob_topics = {t for t in world.bus.topics if not t.startswith("/ned/")}
    world.remove("ned")
    assert ned_topics(world.bus.topics) == []
    assert set(world.bus.topics) == bob_topics  # the rest untouched
    assert sorted(told) == [
        ("/ned/joint_states", "arm ned was removed"),
        ("/ned/status", "arm ned was removed"),
    ]
    # A new arm under the same name advertises them again, and reaches the subscriber.
    states.clear()
    world.spawn("ned", at=(1, 0))
    assert ned_topics(world.bus.topics) == before
    world.step()
    assert states and states[-1].name[0].startswith("ned_")


# -- live ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[WorldProcess]:
    runtime = tmp_path_factory.mktemp("runtime")
    process = WorldProcess(runtime, "bob", "ned", "--at", "0,0", "1,0", "--no-viewer", "--realtime")
    try:
        yield process
    finally:
        os.kill(process.pid, signal.SIGCONT)  # in case a test left it stopped
        assert process.stop() == 0


def echo(live: WorldProcess, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [*ARMFLEET, "topic", "echo", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=runtime_env(live.runtime_dir),
    )


def finish(process: subprocess.Popen[str]) -> tuple[int, str, str]:
    try:
        out, err = process.communicate(timeout=HUNG_S)
    except subprocess.TimeoutExpired:
        process.kill()
        out, err = process.communicate()
        raise AssertionError(f"echo still running after {HUNG_S} s: {err}") from None
    return process.returncode, out, err


def wait_for_subscription(live: WorldProcess, count: int) -> None:
    with armfleet.connect(live.address) as client:
        deadline = time.monotonic() + HUNG_S
        while client.call("info")["subscriptions"] < count:
            assert time.monotonic() < deadline, "echo never subscribed"
            time.sleep(0.05)


def test_removing_an_arm_ends_echoes_of_its_topics_and_topic_list_forgets_them(
    live: WorldProcess,
) -> None:
    listed = cli(live.runtime_dir, "topic", "list")
    assert listed.returncode == 0, listed.stderr
    topics = listed.stdout.split()
    # ned has the topics bob has (same model), and they are listed before the removal
    bob_like = sorted(t.replace("/bob/", "/ned/", 1) for t in topics if t.startswith("/bob/"))
    assert ned_topics(topics) == bob_like and len(bob_like) >= 6
    streaming = echo(live, "/ned/joint_states")  # a message every step
    waiting = echo(live, "/ned/position_controller/commands", "--once")  # never a message
    wait_for_subscription(live, 2)
    removed = cli(live.runtime_dir, "remove", "ned")
    assert removed.returncode == 0, removed.stderr
    for process, topic in (
        (streaming, "/ned/joint_states"),
        (waiting, "/ned/position_controller/commands"),
    ):
        code, _, err = finish(process)
        assert code == 2, err
        assert err.strip() == f"armfleet: error: topic {topic} is gone: arm ned was removed"
    listed = cli(live.runtime_dir, "topic", "list")
    assert ned_topics(listed.stdout.split()) == []
    again = cli(live.runtime_dir, "topic", "echo", "/ned/joint_states", "--once")
    assert again.returncode == 2
    assert "unknown topic '/ned/joint_states'" in again.stderr


@pytest.mark.parametrize(
    ("args", "code", "says"),
    [
        pytest.param(
            ["/bob/position_controller/commands", "--once"],
            2,
            f"no message on /bob/position_controller/commands within {ECHO_TIMEOUT_S:g} s",
            id="--once on a silent topic -> error after the timeout, exit 2",
        ),
        pytest.param(
            ["/bob/joint_states"],
            0,
            "",
            id="no --once on a busy topic -> prints for the timeout, exit 0",
        ),
    ],
)
def test_echo_timeout_ends_the_command(
    live: WorldProcess, args: list[str], code: int, says: str
) -> None:
    started = time.monotonic()
    returncode, out, err = finish(echo(live, *args, "--timeout", str(ECHO_TIMEOUT_S)))
    assert time.monotonic() - started >= ECHO_TIMEOUT_S  # it did wait that long
    assert returncode == code, err
    if says:
        assert err.strip() == f"armfleet: error: {says}"
    else:
        assert out.count("---") >= 1  # it echoed


def test_echo_timeout_ends_the_command_when_the_world_hangs(live: WorldProcess) -> None:
    process = echo(live, "/bob/joint_states", "--once", "--timeout", str(ECHO_TIMEOUT_S))
    os.kill(live.pid, signal.SIGSTOP)  # the world stops answering, at any point of the echo
    try:
        code, out, err = finish(process)
    finally:
        os.kill(live.pid, signal.SIGCONT)
    if out:  # it caught a message before the world stopped
        assert code == 0, err
    else:  # else it failed in one line
        assert code == 2, err
        assert err.count("\n") == 1 and err.startswith("armfleet: "), err
