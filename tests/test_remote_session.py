"""Two terminals' worth: a world in one process, clients in others, one shared simulation."""

from __future__ import annotations

import re
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.messages import JointState
from tests.remote_world import WorldProcess, api_threads, cli, runtime_file, wait_until

#: Tracking of a finished motion: the controller holds within 1e-3 rad.
HOLD_TOLERANCE_RAD = 2e-3


@pytest.fixture
def world(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[WorldProcess]:
    """``armfleet spawn bob --at 0,0`` (paced to the wall clock, so it leaves the CPU to the
    clients) running in its own process; clients find it by the
    runtime file in ``tmp_path``."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    process = WorldProcess(tmp_path, "bob", "--at", "0,0", "--no-viewer", "--realtime")
    yield process
    assert process.stop() == 0
    assert not runtime_file(tmp_path).exists()  # removed on exit
    assert not api_threads()


def test_a_client_spawns_moves_and_watches_an_arm_in_another_process(world: WorldProcess) -> None:
    with armfleet.connect() as client:
        assert client.address == world.address
        carol = client.spawn("carol", model="panda", at=(2, 0))
        assert list(client.arms) == ["bob", "carol"]
        assert carol.joint_names[0] == "carol_panda_joint1"
        start = carol.positions
        states: list[JointState] = []
        lock = threading.Lock()

        def keep(state: JointState) -> None:
            with lock:
                states.append(state)

        subscription = client.subscribe("/carol/joint_states", keep)
        target = start + np.array([0.4, -0.2, 0.3, 0.3, 0.0, 0.2, -0.3])
        carol.move_to(target)
        final = carol.wait(timeout=30)
        assert np.abs(final.position[:7] - target).max() < HOLD_TOLERANCE_RAD
        assert wait_until(lambda: bool(states) and states[-1].stamp >= final.stamp)
        subscription.cancel()
        with lock:
            seen = np.array([s.position[0] for s in states])
            stamps = [s.stamp for s in states]
        # The stream shows the motion itself, in order: joint 1 went from start to target.
        assert stamps == sorted(stamps)
        assert seen.min() < start[0] + 0.05 and seen.max() > target[0] - HOLD_TOLERANCE_RAD
        assert np.any((seen > start[0] + 0.1) & (seen < target[0] - 0.1))
        # bob, in the same world, was not moved by carol's command.
        bob = client.arm("bob")
        assert np.abs(bob.positions - np.array(bob_home())).max() < HOLD_TOLERANCE_RAD
        assert isinstance(carol.joint_state, JointState)


def bob_home() -> list[float]:
    from armfleet.description import ModelLibrary

    return list(ModelLibrary().expand("panda", "").home)


def test_the_cli_adds_an_arm_to_the_running_world_moves_and_echoes_it(
    world: WorldProcess, tmp_path: Path
) -> None:
    spawned = cli(tmp_path, "spawn", "carol", "--at", "2,0")
    assert spawned.returncode == 0, spawned.stderr
    stages = [line for line in spawned.stdout.splitlines() if line.startswith("[carol]")]
    assert [s.split(" (")[0] for s in stages] == [
        f"[carol] {stage.value}" for stage in armfleet.BringupStage
    ]
    assert world.process.poll() is None  # no second world: carol joined this one

    target = ["0.3", "-0.5", "0.1", "-2.0", "0.0", "1.6", "0.8"]
    moved = cli(tmp_path, "move", "carol", "--joints", *target, "--wait")
    assert moved.returncode == 0, moved.stderr
    assert "carol: holding" in moved.stdout

    echoed = cli(tmp_path, "topic", "echo", "/carol/joint_states", "--once")
    assert echoed.returncode == 0, echoed.stderr
    import yaml

    message = yaml.safe_load(echoed.stdout.split("---")[0])
    assert message["name"][0] == "carol_panda_joint1"
    assert np.abs(np.array(message["position"][:7]) - np.array(target, dtype=float)).max() < (
        HOLD_TOLERANCE_RAD
    )

    listed = cli(tmp_path, "arms")
    assert listed.returncode == 0, listed.stderr
    assert [line.split()[0] for line in listed.stdout.splitlines()[1:3]] == ["bob", "carol"]
    topics = cli(tmp_path, "topic", "list", "-t")
    assert "/carol/joint_states [JointState]" in topics.stdout.splitlines()

    removed = cli(tmp_path, "remove", "carol")
    assert removed.returncode == 0, removed.stderr
    with armfleet.connect() as client:
        assert client.info().arms == ("bob",)


def test_pause_stops_at_one_step_still_serves_requests_and_step_advances_exactly(
    world: WorldProcess,
) -> None:
    with armfleet.connect() as client:
        bob = client.arm("bob")
        paused_at = client.pause()
        info = client.info()
        assert info.paused and info.time_s == paused_at and info.realtime_factor == 0.0
        before = bob.positions
        bob.move_to(before + 0.2)  # accepted while paused, but nothing moves
        with pytest.raises(armfleet.ArmfleetError, match=r"bob is still moving after 0\.3 s"):
            bob.wait(timeout=0.3)
        assert client.info().time_s == paused_at
        assert np.abs(bob.positions - before).max() == 0.0
        assert client.step(50) == pytest.approx(paused_at + 50 * info.dt_s)
        assert client.resume() == pytest.approx(paused_at + 50 * info.dt_s)
        bob.wait(timeout=30)
        assert np.abs(bob.positions - (before + 0.2)).max() < HOLD_TOLERANCE_RAD
        assert not client.info().paused
        with pytest.raises(armfleet.ArmfleetError, match="running; pause it first"):
            client.step()


def test_a_stopping_world_ends_subscriptions_and_requests_fail_fast(world: WorldProcess) -> None:
    with armfleet.connect(timeout=2.0) as client:
        subscription = client.subscribe("/bob/joint_states", lambda state: None, rate_hz=10)
        assert subscription.active
        assert world.stop() == 0
        assert subscription.wait_ended(timeout=10)
        assert isinstance(subscription.error, armfleet.remote.ConnectionLost)
        client.timeout = 0.5
        with pytest.raises(armfleet.remote.RequestTimeout, match="no answer"):
            client.info()


def test_the_live_api_example_runs_as_written(world: WorldProcess) -> None:
    page = (Path(__file__).resolve().parents[1] / "docs" / "live-api.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", page, flags=re.DOTALL)
    (example,) = [block for block in blocks if "armfleet.connect()" in block]
    exec(compile(example, "docs/live-api.md", "exec"), {})
    with armfleet.connect() as client:
        assert client.info().arms == ("bob", "carol")
        assert client.info().streams == 0  # the example cleaned up after itself


def test_spawn_options_publish_and_reset_reach_the_world(world: WorldProcess) -> None:
    start = [0.1, -0.5, 0.2, -2.0, 0.1, 1.8, 0.5]
    with armfleet.connect() as client:
        dave = client.spawn(
            "dave",
            model="panda",
            at="3,0,0,90",
            initial_positions=start,
            parameters={"position_controller": {"max_acceleration_rad_s2": 2.0}},
        )
        assert dave.pose == armfleet.SpawnPose(3, 0, 0, 90)
        assert np.abs(dave.positions - start).max() < HOLD_TOLERANCE_RAD
        target = np.array(start) + 0.1
        client.publish("/dave/position_controller/commands", target)
        dave.wait(timeout=30)
        assert np.abs(dave.positions - target).max() < HOLD_TOLERANCE_RAD
        dave.reset_stop()  # nothing to reset: accepted all the same
        assert dave.mode is armfleet.messages.ArmMode.HOLDING
        assert client.topics()["/dave/position_controller/commands"].command
        with pytest.raises(armfleet.ArmfleetError, match="max_acceleration_rad_s2 = -1"):
            client.spawn(
                "erin",
                at=(4, 0),
                parameters={"position_controller": {"max_acceleration_rad_s2": -1.0}},
            )
