"""Eight clients at once: each spawns an arm and commands it; bring-ups never interleave,
every command is applied, and the world keeps stepping all along."""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.messages import BringupEvent, BringupStage
from tests.remote_world import WorldProcess, api_threads

CLIENTS = 8
HOLD_TOLERANCE_RAD = 2e-3
#: Wall time [s] the world may stand still while an arm's model loads.
MAX_STAND_S = 2.0


@pytest.fixture
def world(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[WorldProcess]:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    # Paced to the wall clock, so the world leaves CPU to the 8 client threads.
    process = WorldProcess(tmp_path, "bob", "--at", "0,0", "--no-viewer", "--realtime")
    yield process
    assert process.stop() == 0
    assert not api_threads()


def test_eight_clients_spawn_and_command_arms_at_once(world: WorldProcess) -> None:
    monitor = armfleet.connect()
    events: list[BringupEvent] = []
    monitor.subscribe("/bringup", events.append, queue_size=1000)
    barrier = threading.Barrier(CLIENTS)
    errors: list[BaseException] = []
    targets: dict[str, np.ndarray] = {}
    reached: dict[str, np.ndarray] = {}
    lock = threading.Lock()

    def work(index: int) -> None:
        name = f"arm{index}"
        try:
            with armfleet.connect(timeout=30.0) as client:
                barrier.wait(timeout=30)
                arm = client.spawn(name, at=(index + 1.0, 0.0))
                target = arm.positions + 0.05 * (index + 1) * np.array([1, -1, 1, 1, 1, -1, 1])
                arm.move_to(target)
                state = arm.wait(timeout=60)
                with lock:
                    targets[name] = target
                    reached[name] = state.position[:7]
        except BaseException as exc:
            with lock:
                errors.append(exc)

    times: list[tuple[float, float]] = []  # (wall, simulated) [s]
    done = threading.Event()

    def sample() -> None:
        with armfleet.connect(timeout=30.0) as client:
            while not done.is_set():
                times.append((time.monotonic(), client.info().time_s))
                done.wait(0.01)
            times.append((time.monotonic(), client.info().time_s))

    sampler = threading.Thread(target=sample)
    sampler.start()
    workers = [threading.Thread(target=work, args=(i,)) for i in range(CLIENTS)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=120)
    done.set()
    sampler.join(timeout=60)
    try:
        assert not errors, errors
        names = [f"arm{i}" for i in range(CLIENTS)]
        # Every command applied: each arm holds its own target.
        for name in names:
            assert np.abs(reached[name] - targets[name]).max() < HOLD_TOLERANCE_RAD, name
        assert sorted(monitor.info().arms) == sorted(["bob", *names])
        # Bring-ups strictly one at a time: each arm's four stages are contiguous, in order.
        assert _wait_for(lambda: len(events) == 4 * CLIENTS)
        order = [(e.arm, e.stage) for e in events]
        stages = list(BringupStage)
        for start in range(0, len(order), 4):
            arm = order[start][0]
            assert order[start : start + 4] == [(arm, stage) for stage in stages], order
        assert sorted({arm for arm, _ in order}) == sorted(names)
        # The world never stopped stepping: simulated time never went back, moved on over
        # the run, and never stood still for long. Loading an arm's model holds the
        # stepping thread for a moment, so two samples 10 ms apart may share a time on a
        # loaded machine; a world held for the eight bring-ups would stand for seconds.
        assert len(times) >= 3
        sims = [sim for _, sim in times]
        assert all(later >= earlier for earlier, later in itertools.pairwise(sims))
        assert sims[-1] > sims[0]
        assert _longest_stand_s(times) < MAX_STAND_S
    finally:
        monitor.close()


def _longest_stand_s(times: list[tuple[float, float]]) -> float:
    """The longest wall time [s] over which the sampled simulated time did not move."""
    longest, since = 0.0, times[0]
    for wall, sim in times[1:]:
        if sim > since[1]:
            since = (wall, sim)
        longest = max(longest, wall - since[0])
    return longest


def _wait_for(condition: object, timeout: float = 10.0) -> bool:
    from tests.remote_world import wait_until

    return wait_until(condition, timeout)
