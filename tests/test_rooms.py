"""The house (docs/design.md): rooms with rules, a core that loads no optional package,
front ends that attach to the world, and a one-line refusal when an extra is missing."""

from __future__ import annotations

import ast
import itertools
import json
import subprocess
import sys
from pathlib import Path

import pytest

import armfleet
from armfleet.world import WorldListener

PACKAGE = Path(armfleet.__file__).parent
#: Installed by the extras (pyproject.toml), never by the core.
OPTIONAL = ("ray", "pyarrow", "foxglove", "gymnasium", "pettingzoo", "matplotlib", "tqdm")
#: Blocks imports of the given top-level names, as if their extra were not installed.
BLOCKER = """
import sys
class _Missing:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in {blocked!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None
sys.meta_path.insert(0, _Missing())
"""


def _python(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )


def test_import_armfleet_loads_no_optional_package() -> None:
    code = (
        "import sys, json, armfleet; "
        "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"
    )
    result = _python(code)
    assert result.returncode == 0, result.stderr
    loaded = set(json.loads(result.stdout))
    assert not loaded & set(OPTIONAL), loaded & set(OPTIONAL)
    # Nor the simulator, the live API's transport or the viewer: they load on first use.
    later = {"pinocchio", "ompl", "coal", "zmq", "meshcat", "tornado", "mcap"}
    assert not loaded & later, loaded & later


def test_names_that_load_on_first_use_resolve_to_their_room() -> None:
    from armfleet.planning.failure import PlanningFailed
    from armfleet.remote import connect
    from armfleet.sweeps import SweepResult, sweep
    from armfleet.world.world import World

    assert armfleet.connect is connect and armfleet.World is World
    assert armfleet.sweep is sweep and armfleet.SweepResult is SweepResult
    assert armfleet.PlanningFailed is PlanningFailed
    assert set(armfleet.__all__) <= set(dir(armfleet))
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        armfleet.nothing  # noqa: B018


def test_the_root_holds_at_most_six_modules() -> None:
    modules = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(modules) <= 6, modules


@pytest.mark.parametrize(
    "room", sorted(p.parent.name for p in PACKAGE.glob("*/__init__.py")), ids=str
)
def test_every_room_states_its_rule(room: str) -> None:
    docstring = ast.get_docstring(ast.parse((PACKAGE / room / "__init__.py").read_text()))
    assert docstring is not None and "Rule:" in docstring, f"armfleet.{room} states no rule"


def test_the_user_handle_carries_no_planner_plumbing() -> None:
    for plumbing in ("start_plan", "publish_planned", "follow_motion", "tool_position"):
        assert not hasattr(armfleet.Arm, plumbing), plumbing


class _Heard(WorldListener):
    def __init__(self) -> None:
        self.heard: list[str] = []

    def on_arm_ready(self, arm: armfleet.Arm) -> None:
        self.heard.append(f"ready {arm.name}")

    def on_arm_removed(self, name: str) -> None:
        self.heard.append(f"removed {name}")

    def on_object_added(self, obj: armfleet.WorldObject) -> None:
        self.heard.append(f"added {obj.name}")

    def on_object_removed(self, name: str) -> None:
        self.heard.append(f"gone {name}")

    def on_step(self) -> None:
        if not self.heard or self.heard[-1] != "step":
            self.heard.append("step")

    def on_close(self) -> None:
        self.heard.append("close")


class _Broken(WorldListener):
    def on_step(self) -> None:
        raise RuntimeError("a front end that fails")


def test_front_ends_hear_the_world_in_order_and_a_failing_one_is_detached() -> None:
    world = armfleet.World()
    listener, broken = _Heard(), _Broken()
    world.attach(listener)
    world.attach(broken)
    world.spawn("bob", at=(0, 0))
    world.add_object("box", "box", size=(0.1, 0.1, 0.1), at=(0.6, 0.0, 0.05))
    world.run(0.01)  # the broken listener raises at the first step and is detached
    world.remove_object("box")
    world.remove("bob")
    world.detach(broken)  # already detached: nothing happens
    world.close()
    assert listener.heard == [
        "step",  # the bring-up steps the world until the arm is ready
        "ready bob",
        "added box",
        "step",
        "gone box",
        "removed bob",
        "close",
    ]


def test_attach_takes_only_a_listener() -> None:
    with armfleet.World() as world, pytest.raises(armfleet.ArmfleetError, match="WorldListener"):
        world.attach(print)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("blocked", "call", "extra"),
    [
        pytest.param(
            ("foxglove",),
            "armfleet.World().serve_foxglove(0)",
            "foxglove",
            id="foxglove-without-its-extra",
        ),
        pytest.param(
            ("ray", "pyarrow"), "armfleet.sweep('reach', runs=1)", "sweeps", id="sweep-without-ray"
        ),
        pytest.param(("gymnasium",), "import armfleet.envs", "envs", id="envs-without-gymnasium"),
    ],
)
def test_a_missing_extra_is_one_line_with_the_pip_command(
    blocked: tuple[str, ...], call: str, extra: str
) -> None:
    code = BLOCKER.format(blocked=set(blocked)) + (
        "import armfleet\n"
        "try:\n"
        f"    {call}\n"
        "except armfleet.ArmfleetError as exc:\n"
        "    print(type(exc).__name__, exc)\n"
    )
    result = _python(code)
    assert result.returncode == 0, result.stderr
    line = result.stdout.strip()
    assert line.startswith("MissingExtra") and "\n" not in line, line
    assert f"pip install 'armfleet[{extra}]'" in line, line


@pytest.mark.parametrize(
    ("blocked", "argv", "extra"),
    [
        pytest.param(("ray",), ["sweep", "reach", "--runs", "1"], "sweeps", id="sweep"),
        pytest.param(("pyarrow",), ["sweep-report", "x.parquet"], "sweeps", id="sweep-report"),
        pytest.param(
            ("foxglove",),
            ["spawn", "bob", "--at", "0,0", "--foxglove", "0", "--no-viewer", "--new-world",
             "--no-api", "--duration", "0"],
            "foxglove",
            id="spawn-foxglove",
        ),
    ],
)  # fmt: skip
def test_the_cli_refuses_a_missing_extra_with_exit_2(
    blocked: tuple[str, ...], argv: list[str], extra: str, tmp_path: Path
) -> None:
    code = BLOCKER.format(blocked=set(blocked)) + (
        f"from armfleet.cli.main import main\nsys.exit(main({argv!r}))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        cwd=tmp_path,
        env={**_environment(), "XDG_RUNTIME_DIR": str(tmp_path)},
    )
    assert result.returncode == 2, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and f"pip install 'armfleet[{extra}]'" in lines[0], lines


def _environment() -> dict[str, str]:
    import os

    return dict(os.environ)


def test_the_core_commands_start_without_any_extra(tmp_path: Path) -> None:
    code = BLOCKER.format(blocked=set(OPTIONAL)) + (
        "from armfleet.cli.main import main\nsys.exit(main(['models']))\n"
    )
    result = _python(code)
    assert result.returncode == 0, result.stderr
    assert "panda" in result.stdout


def test_a_sweep_naming_the_scenarios_old_room_still_finds_them() -> None:
    from armfleet.scenarios.handover import handover
    from armfleet.sweeps.task_reference import task_reference

    reference = task_reference("armfleet.sweeps.scenarios.handover:handover")
    assert reference.load() is handover


def _layers() -> list[list[str]]:
    import tomllib

    config = tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())
    contract = next(c for c in config["tool"]["importlinter"]["contracts"] if c["id"] == "rooms")
    return [
        [name.strip().removeprefix("armfleet.") for name in layer.split("|")]
        for layer in contract["layers"]
    ]


def test_the_layers_name_every_room_and_root_module() -> None:
    named = {room for layer in _layers() for room in layer}
    rooms = {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    modules = {p.stem for p in PACKAGE.glob("*.py")} - {"__init__"}
    assert named == rooms | modules, named ^ (rooms | modules)


def test_the_design_doc_shows_the_rooms_in_the_contracts_order() -> None:
    """docs/design.md's table of rooms is the layers contract, top first."""
    text = (PACKAGE.parent / "docs" / "design.md").read_text()
    section = text.split("## The rooms", 1)[1].split("\n## ", 1)[0]
    shown: list[str] = []
    for line in section.splitlines():
        cells = [cell.strip() for cell in line.split("|")]
        if len(cells) > 3 and cells[2].startswith("`"):
            shown += [name.strip("` ") for name in cells[2].split(",")]
    order = [room for layer in _layers() for room in layer]
    assert sorted(shown) == sorted(order)
    # Every room appears below every room of a higher layer.
    position = {room: shown.index(room) for room in shown}
    layers = _layers()
    for upper, lower in itertools.pairwise(layers):
        assert max(position[r] for r in upper) < min(position[r] for r in lower), (upper, lower)


@pytest.mark.parametrize(
    "room", sorted(p.parent.name for p in PACKAGE.glob("*/__init__.py")), ids=str
)
def test_every_name_a_room_exports_is_what_it_names_not_a_module(room: str) -> None:
    """A room's names load on first use; one that is also a module's name must not leave
    the module in its place (``armfleet.objects.object_spec`` is the function)."""
    import importlib
    import types

    package = importlib.import_module(f"armfleet.{room}")
    for name in getattr(package, "__all__", ()):
        value = getattr(package, name)
        assert not isinstance(value, types.ModuleType), f"armfleet.{room}.{name} is a module"
