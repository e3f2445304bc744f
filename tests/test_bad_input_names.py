"""Names, frame owners and start poses: each bad input refused in one line on every surface.

Issue #14, items 1, 6, 7 (arms and objects) and 11(c). One catalogue, four surfaces: the Python API
(``World.spawn`` / ``World.add_object``), the CLI against a running world
(``armfleet spawn`` / ``add-object``, a subprocess), a launch spec through
``armfleet launch --check`` (a subprocess), and a live-API client. Each surface
starts from the same scene: Pandas bob at (0, 0) and x at (0, 3), a static box
``carol_tool0`` at (3, 3) on the floor and a static ``crate`` floating 0.5 m above
(3, -3). After a refusal the scene must be as it was: same arms, objects and
bodies, bob holding (no protective stop), and the process alive.
"""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.checks.names import MAX_NAME_LENGTH
from armfleet.errors import (
    ArmfleetError,
    FrameInUse,
    InvalidArmName,
    ObjectCollision,
    ObjectError,
    StartPoseCollision,
)
from armfleet.messages import ArmMode
from armfleet.remote import RemoteError
from tests.remote_world import ARMFLEET, WorldProcess, cli, runtime_env

#: A settled arm's joints drift less than this over 0.2 s [rad] (as in test_bad_input.py).
HOLD_DRIFT_RAD = 1e-4
#: A Panda with joint4 at its lower limit (elbow shut): the hand folds into link1.
FOLDED = (0.0, 0.3, 0.0, -3.0718, 0.0, 1.57, 0.7854)

ARMS = (("bob", (0.0, 0.0)), ("x", (0.0, 3.0)))
#: name, size [m], centre [m]; both static.
OBJECTS = (
    ("carol_tool0", (0.1, 0.1, 0.1), (3.0, 3.0, 0.05)),
    ("crate", (0.3, 0.3, 0.3), (3.0, -3.0, 0.5)),
)


@dataclass(frozen=True)
class NewArm:
    name: str
    at: tuple[float, ...]
    model: str = "panda"
    initial_positions: tuple[float, ...] | None = None


@dataclass(frozen=True)
class NewObject:
    name: str
    at: tuple[float, float, float]
    size: tuple[float, float, float] = (0.1, 0.1, 0.1)
    mass: float = 0.0


SURFACES = frozenset({"python", "cli", "spec", "live"})


@dataclass(frozen=True)
class Bad:
    """What is tried, the error the world raises and what its one line must say.

    ``spec_says`` replaces ``says`` for a launch spec where the spec's own order
    (arms before objects) makes the other party the second claimant.
    """

    what: NewArm | NewObject
    error: type[ArmfleetError]
    says: str
    spec_says: str | None = None
    surfaces: frozenset[str] = SURFACES


LONG = "a" * (MAX_NAME_LENGTH + 1)
HUGE = "b" * 1300  # PyBullet's URDF loader segfaulted from about 1,255

CASES = [
    pytest.param(
        Bad(NewArm(LONG, (6.0, 0.0)), InvalidArmName, "is too long (65 characters)"),
        id="arm name of 65 characters -> InvalidArmName naming the 64 limit",
    ),
    pytest.param(
        Bad(NewArm(HUGE, (6.0, 0.0)), InvalidArmName, "is too long (1300 characters)"),
        id="arm name of 1300 characters (used to segfault) -> InvalidArmName, process lives",
    ),
    pytest.param(
        Bad(NewArm("ground", (6.0, 0.0)), InvalidArmName, "'ground' is reserved"),
        id="arm named ground (the floor on /collisions) -> InvalidArmName, reserved",
    ),
    pytest.param(
        Bad(NewObject(LONG, (6.0, 6.0, 0.05)), ObjectError, "name: is too long (65 characters)"),
        id="object name of 65 characters -> ObjectError naming the 64 limit",
    ),
    pytest.param(
        Bad(
            NewArm("x_panda", (6.0, 3.0), model="xarm7"),
            FrameInUse,
            "arm x_panda would own frame 'x_panda_joint1', which is arm x's already",
        ),
        id="xarm7 x_panda beside Panda x -> FrameInUse naming arm x",
    ),
    pytest.param(
        Bad(
            NewArm("carol", (6.0, 6.0)),
            FrameInUse,
            "arm carol would own frame 'carol_tool0', which is object carol_tool0's already",
            spec_says="object carol_tool0 would own frame 'carol_tool0', which is arm carol's",
        ),
        id="arm carol after object carol_tool0 -> FrameInUse naming the other owner",
    ),
    pytest.param(
        Bad(
            NewObject("bob_tool0", (-3.0, 0.0, 0.05)),
            FrameInUse,
            "object bob_tool0 would own frame 'bob_tool0', which is arm bob's already",
        ),
        id="object named like bob's flange -> FrameInUse naming arm bob",
    ),
    pytest.param(
        Bad(NewArm("toby", (0.3, 0.0)), StartPoseCollision, "toby would touch bob at its start"),
        id="Panda 0.3 m from bob (passed the old 0.25 m rule) -> StartPoseCollision naming bob",
    ),
    pytest.param(
        Bad(NewArm("toby", (0.0, 0.0)), StartPoseCollision, "toby would touch bob at its start"),
        id="Panda on bob's base -> StartPoseCollision naming bob",
    ),
    pytest.param(
        Bad(
            NewArm("toby", (6.0, 0.0, -0.3)),
            StartPoseCollision,
            "toby would touch ground at its start",
        ),
        id="Panda sunk 0.3 m into the floor -> StartPoseCollision naming ground",
    ),
    pytest.param(
        Bad(NewArm("toby", (3.0, -3.0)), StartPoseCollision, "toby would touch crate at its"),
        id="Panda under a static crate -> StartPoseCollision naming the crate",
    ),
    pytest.param(
        Bad(
            NewArm("toby", (6.0, 0.0), initial_positions=FOLDED),
            StartPoseCollision,
            "toby would touch itself at its start pose (toby_panda_",
            surfaces=frozenset({"python", "spec", "live"}),  # the CLI sets no initial positions
        ),
        id="joint4 at its limit folds the hand into link1 -> StartPoseCollision naming itself",
    ),
    pytest.param(
        Bad(
            NewObject("mitt", (0.307, 0.0, 0.59)),
            ObjectCollision,
            "object 'mitt': at: it would touch bob there (bob_panda_",
            spec_says="bob would touch mitt at its start pose",  # the spec places objects first
        ),
        id="static box around bob's hand (stopped bob) -> ObjectCollision naming bob",
    ),
    pytest.param(
        Bad(
            NewObject("cup", (3.0, -3.0, 0.5), mass=0.5),
            ObjectCollision,
            "object 'cup': at: it would overlap crate there",
        ),
        id="0.5 kg box inside the static crate (thrown out) -> ObjectCollision naming the crate",
    ),
    pytest.param(
        Bad(
            NewObject("cup", (6.0, 6.0, 0.0), mass=0.5),
            ObjectCollision,
            "object 'cup': at: it would overlap ground there (50.0 mm into it",
        ),
        id="0.5 kg box half into the floor (thrown up) -> ObjectCollision naming ground",
    ),
]


# -- the Python API -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def scene() -> Iterator[armfleet.World]:
    with armfleet.World() as world:
        for name, at in ARMS:
            world.spawn(name, at=at)
        for name, size, centre in OBJECTS:
            world.add_object(name, "box", size=size, mass=0.0, at=centre)
        yield world


def _try_python(world: armfleet.World, what: NewArm | NewObject) -> None:
    if isinstance(what, NewArm):
        world.spawn(what.name, what.model, what.at, initial_positions=what.initial_positions)
    else:
        world.add_object(what.name, "box", size=what.size, mass=what.mass, at=what.at)


@pytest.mark.parametrize("bad", CASES)
def test_python_api(scene: armfleet.World, bad: Bad) -> None:
    world, bob = scene, scene.arm("bob")
    bodies = p.getNumBodies(physicsClientId=world.physics_client)
    stops, before = world.safety.stops, bob.positions
    with pytest.raises(bad.error) as raised:
        _try_python(world, bad.what)
    message = str(raised.value)
    assert bad.says in message and "\n" not in message and len(message) < 300, message
    assert tuple(world.arms) == ("bob", "x")
    assert tuple(world.objects) == ("carol_tool0", "crate")
    assert p.getNumBodies(physicsClientId=world.physics_client) == bodies
    world.run(0.2)
    assert world.safety.stops == stops
    assert np.max(np.abs(bob.positions - before)) < HOLD_DRIFT_RAD


# -- the CLI and the live API, against one world in another process ------------------------
@dataclass(frozen=True)
class Running:
    runtime: Path
    address: str


@pytest.fixture(scope="module")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    runtime = tmp_path_factory.mktemp("runtime")
    names = [name for name, _ in ARMS]
    at = [f"{x:g},{y:g}" for _, (x, y) in ARMS]
    with WorldProcess(runtime, *names, "--at", *at, "--no-viewer") as world:
        with armfleet.connect(world.address) as client:
            for name, size, centre in OBJECTS:
                client.add_object(name, "box", size=size, mass=0.0, at=centre)
        yield Running(runtime, world.address)


def _assert_world_as_it_was(running: Running) -> None:
    with armfleet.connect(running.address) as client:
        assert client.info().arms == ("bob", "x")
        assert tuple(client.objects) == ("carol_tool0", "crate")
        assert all(arm.mode is ArmMode.HOLDING for arm in client.arms.values())


def _cli_arguments(what: NewArm | NewObject) -> list[str]:
    if isinstance(what, NewArm):
        at = ",".join(f"{v:g}" for v in what.at)
        return ["spawn", what.name, "--at", at, "--model", what.model]
    return [
        "add-object", what.name, "box", "--size", *map(str, what.size), "--mass", str(what.mass),
        "--at", *map(str, what.at),
    ]  # fmt: skip


@pytest.mark.parametrize("bad", CASES)
def test_cli(running: Running, bad: Bad) -> None:
    if "cli" not in bad.surfaces:
        pytest.skip("not something the CLI can express")
    result = cli(running.runtime, *_cli_arguments(bad.what))
    assert result.returncode == 2, result
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert bad.says in lines[0], lines[0]
    _assert_world_as_it_was(running)


def test_cli_fleet_joining_a_world_is_checked_whole(running: Running) -> None:
    """Two arms typed together, the second touching the first: neither is sent to the world
    (the first used to come up, then the second was refused)."""
    result = cli(running.runtime, "spawn", "p", "q", "--at", "6,0", "6.3,0")
    assert result.returncode == 2, result
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert "q would touch p at its start pose" in lines[0], lines[0]
    assert "joining" not in result.stdout and "[p]" not in result.stdout, result.stdout
    _assert_world_as_it_was(running)


@pytest.mark.parametrize("bad", CASES)
def test_live_api(running: Running, bad: Bad) -> None:
    what = bad.what
    with armfleet.connect(running.address) as client, pytest.raises(RemoteError) as raised:
        if isinstance(what, NewArm):
            client.spawn(what.name, what.model, what.at, initial_positions=what.initial_positions)
        else:
            client.add_object(what.name, "box", size=what.size, mass=what.mass, at=what.at)
    assert raised.value.kind == bad.error.__name__
    assert bad.says in str(raised.value) and "\n" not in str(raised.value)
    _assert_world_as_it_was(running)


# -- a launch spec, through ``armfleet launch --check`` ------------------------------------
def spec_text(what: NewArm | NewObject) -> str:
    """The scene as a spec, with ``what`` last among the arms or the objects."""
    arms = [NewArm(name, at) for name, at in ARMS]
    objects = [NewObject(name, at, size) for name, size, at in OBJECTS]
    if isinstance(what, NewArm):
        arms.append(what)
    else:
        objects.append(what)
    lines = ["world: {viewer: false}", "arms:"]
    for arm in arms:
        lines += [f"  - name: {arm.name}", f"    model: {arm.model}", f"    at_m: {list(arm.at)}"]
        if arm.initial_positions is not None:
            lines.append(f"    initial_positions: {list(arm.initial_positions)}")
    lines.append("objects:")
    for obj in objects:
        lines += [
            f"  - name: {obj.name}", "    shape: box", f"    size_m: {list(obj.size)}",
            f"    mass_kg: {obj.mass}", f"    at_m: {list(obj.at)}",
        ]  # fmt: skip
    return "\n".join(lines) + "\n"


def test_the_scene_itself_passes_the_check(tmp_path: Path) -> None:
    spec = tmp_path / "scene.yaml"
    spec.write_text(spec_text(NewObject("cup", (-3.0, -3.0, 0.05))))
    result = subprocess.run(
        [*ARMFLEET, "launch", "--check", str(spec)],
        capture_output=True, text=True, env=runtime_env(tmp_path), timeout=120,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "ok: 2 arm(s)" in result.stdout


@pytest.mark.parametrize("bad", CASES)
def test_spec_check(tmp_path: Path, bad: Bad) -> None:
    spec = tmp_path / "bad.yaml"
    spec.write_text(spec_text(bad.what))
    result = subprocess.run(
        [*ARMFLEET, "launch", "--check", str(spec)],
        capture_output=True, text=True, env=runtime_env(tmp_path), timeout=120,
    )  # fmt: skip
    assert result.returncode == 2, result
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert (bad.spec_says or bad.says) in lines[0], lines[0]
    assert f"{spec}:" in lines[0]  # file and line of the entry
