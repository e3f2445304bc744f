"""What the CLI loads before it does anything: only the named command's modules, and none
of the heavy packages a command does not need (structural checks on ``sys.modules``; the
timings are benchmarks/cli_startup.py's)."""

from __future__ import annotations

import argparse
import importlib
import json
import subprocess
import sys

import pytest

from armfleet.cli.main import COMMANDS, build_parser
from armfleet.cli.parser import OneLineParser

#: Packages that cost a start-up tenths of a second each.
HEAVY = ("ray", "matplotlib", "pybullet", "pinocchio", "pyarrow", "coal", "ompl", "mcap", "zmq")
#: Commands that only talk to a running world: they need the live API's transport only.
LIVE_API = (
    "arms", "move", "move-together", "grip", "remove", "reset", "topic", "objects",
    "add-object", "remove-object", "info", "pause", "resume", "step",
)  # fmt: skip
#: Commands whose heavy work (models, recordings, matplotlib, Ray) loads when they run.
OFFLINE = ("models", "plot", "sweep", "sweep-report")


def _loaded_after(code: str) -> set[str]:
    """The top-level packages loaded by ``code`` in a fresh interpreter."""
    script = (
        code
        + "\nimport sys, json; print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=False
    )
    assert result.returncode == 0, result.stderr
    return set(json.loads(result.stdout.strip().splitlines()[-1]))


def test_importing_the_cli_loads_no_heavy_package() -> None:
    loaded = _loaded_after("import armfleet.cli.main")
    assert not loaded & set(HEAVY), loaded & set(HEAVY)


@pytest.mark.parametrize("command", LIVE_API)
def test_a_live_api_command_loads_only_the_transport(command: str) -> None:
    loaded = _loaded_after(f"from armfleet.cli.main import build_parser; build_parser({command!r})")
    assert not loaded & (set(HEAVY) - {"zmq"}), loaded & set(HEAVY)


@pytest.mark.parametrize("command", OFFLINE)
def test_an_offline_command_loads_its_heavy_packages_only_when_it_runs(command: str) -> None:
    loaded = _loaded_after(f"from armfleet.cli.main import build_parser; build_parser({command!r})")
    assert not loaded & set(HEAVY), loaded & set(HEAVY)


def test_the_command_table_is_what_the_modules_add() -> None:
    """COMMANDS names, for each command, the modules that add its parser: built module by
    module, each adds exactly the commands the table gives it."""
    parser = OneLineParser(prog="armfleet")
    subparsers = parser.add_subparsers(dest="command", parser_class=OneLineParser)
    added: dict[str, str] = {}
    for module_name in dict.fromkeys(m for modules in COMMANDS.values() for m in modules):
        module = importlib.import_module(f"armfleet.cli.{module_name}")
        before = set(subparsers.choices)
        if hasattr(module, "add_parsers"):
            module.add_parsers(subparsers)
        elif hasattr(module, "add_parser"):
            module.add_parser(subparsers)
        else:  # the module that extends another command's parser
            assert module_name == "recording_info_command"
            continue
        added |= {name: module_name for name in set(subparsers.choices) - before}
    assert added == {name: modules[0] for name, modules in COMMANDS.items()}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_each_command_parses_alone_as_in_the_whole_parser(command: str) -> None:
    """A command's own parser, built alone, is the one the whole parser holds: the same
    options (spawn and launch with the live API's too)."""

    def options(parser: argparse.ArgumentParser) -> list[str]:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        chosen = sub.choices[command]
        return sorted(s for action in chosen._actions for s in action.option_strings)

    assert options(build_parser(command)) == options(build_parser())
    assert build_parser(command).commands == tuple(COMMANDS)


def test_the_object_commands_offer_the_shapes_the_world_accepts() -> None:
    from armfleet.cli import object_commands
    from armfleet.services import object_services

    assert object_commands.REMOTE_SHAPES == object_services.REMOTE_SHAPES


def test_pybullet_stays_quiet_when_it_loads_after_armfleet() -> None:
    """PyBullet no longer loads with ``import armfleet``; wherever it first loads, its
    build-time banner stays off stderr (the CLI's one-line promise)."""
    code = (
        "import sys, armfleet\n"
        "assert 'pybullet' not in sys.modules\n"
        "world = armfleet.World()\n"
        "world.close()\n"
        "import pybullet\n"
        "print(pybullet.isNumpyEnabled() in (0, 1))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "True" and result.stderr == ""
