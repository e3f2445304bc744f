"""Shared fixtures: DIRECT-mode worlds, a bob/toby pair, the model library; a failing test's
recordings and tracking plots saved to ``test-artifacts/<test id>/``; the slowest files
started first (tests/file_order.py)."""

from __future__ import annotations

import os
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

import armfleet
from armfleet.description import ModelLibrary
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.spec import ArmSpec, FleetSpec
from tests.failure_artifacts import artifacts_root, folder_for, save_artifacts
from tests.file_order import slowest_files_first

#: The recordings a test registered with ``keep_on_failure``.
KEPT_RECORDINGS = pytest.StashKey[list[Path]]()


def pytest_configure(config: pytest.Config) -> None:
    # xdist would start the files with the most tests first, not the order collected.
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False
    # The suite starts hundreds of Python processes (the CLI, worlds, benchmarks, Ray's
    # workers). Where PYTHONDONTWRITEBYTECODE is set, none of them caches armfleet's
    # bytecode, so each compiles its modules from source again: a fifth of the CPU of a
    # CLI command. They may cache it in __pycache__ (git-ignored), as Python does by
    # default; what runs is the same. Set here, before xdist starts its workers.
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    slowest_files_first(items)


@pytest.fixture(scope="session")
def models() -> ModelLibrary:
    return ModelLibrary()


@pytest.fixture
def world() -> Iterator[armfleet.World]:
    """A fresh headless world, closed after the test."""
    with armfleet.World() as new_world:
        yield new_world


@pytest.fixture
def pair(world: armfleet.World) -> armfleet.World:
    """bob at (0, 0) and toby at (1, 0), both Pandas, ready."""
    world.spawn("bob", model="panda", at=(0, 0))
    world.spawn("toby", model="panda", at=(1, 0))
    return world


@pytest.fixture
def keep_on_failure(request: pytest.FixtureRequest) -> Callable[[Path], None]:
    """Register an MCAP recording to save, with its tracking plots, if the test fails."""
    kept: list[Path] = request.node.stash.setdefault(KEPT_RECORDINGS, [])
    return kept.append


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    recordings = item.stash.get(KEPT_RECORDINGS, [])
    if report.when == "call" and report.failed and recordings:
        folder = folder_for(artifacts_root(item.config), item.nodeid)
        try:
            files = save_artifacts([path for path in recordings if path.is_file()], folder)
            text = "\n".join(str(path) for path in files)
        except OSError as exc:
            text = f"could not save the recordings to {folder}: {exc}"
        report.sections.append(("failure artifacts (recording, tracking plots)", text))
    return report


# -- a recorded run, shared by the recording tests ---------------------------------------
@dataclass
class RecordedRun:
    """2 s of bob (moving) and toby, launched from a spec and recorded to ``path``.

    Attributes:
        path: the MCAP file.
        spec: the launch spec given to the recorder.
        topics: the world's topics and message types at the end.
        arms: the live arms' URDFs and joint names, by name.
        messages: every bus message seen by a second listener: (topic, log time [ns], message).
        command: the target sent to bob.
    """

    path: Path
    spec: FleetSpec
    topics: dict[str, type]
    arms: dict[str, tuple[str, tuple[str, ...]]]
    messages: list[tuple[str, int, Any]]
    command: tuple[float, ...]
    dt: float


@pytest.fixture(scope="session")
def recorded_run(tmp_path_factory: pytest.TempPathFactory) -> RecordedRun:
    path = tmp_path_factory.mktemp("recorded") / "run.mcap"
    spec = FleetSpec(
        arms=(
            ArmSpec("bob", "panda", SpawnPose(0.0, 0.0)),
            ArmSpec("toby", "panda", SpawnPose(1.0, 0.0, 0.0, 180.0)),
        ),
        source="the recording tests",
    )
    seen: list[tuple[str, int, Any]] = []
    recorders: list[armfleet.Recorder] = []

    def before_spawn(world: armfleet.World) -> None:
        recorders.append(armfleet.record(world, path, spec=spec))
        world.bus.subscribe_all(lambda t, m: seen.append((t, round(world.time * 1e9), m)))

    world = armfleet.launch(spec, viewer=False, before_spawn=before_spawn)
    try:
        bob = world.arm("bob")
        target = bob.positions + 0.3
        bob.move_to(target)
        world.run(2.0)
        recorders[0].stop()
        arms = {n: (a.description.urdf, a.kinematics.joint_names) for n, a in world.arms.items()}
        return RecordedRun(
            path, spec, world.bus.topics, arms, seen, tuple(target.tolist()), world.dt
        )
    finally:
        world.close()
