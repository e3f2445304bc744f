"""The public names: ``armfleet.__all__`` and the README/issue #2 contract other tools use."""

from __future__ import annotations

import inspect
from importlib import metadata

import pytest

import armfleet


@pytest.mark.parametrize("name", armfleet.__all__)
def test_every_exported_name_resolves(name: str) -> None:
    assert getattr(armfleet, name) is not None


def test_all_has_no_duplicates_and_holds_the_core() -> None:
    assert len(set(armfleet.__all__)) == len(armfleet.__all__)
    assert {"World", "Arm", "ArmfleetError", "__version__"} <= set(armfleet.__all__)


def test_version_is_the_package_version() -> None:
    assert isinstance(armfleet.__version__, str)
    assert armfleet.__version__ == metadata.version("armfleet")
    assert all(part.isdigit() for part in armfleet.__version__.split(".")[:3])


def test_errors_share_one_root() -> None:
    from armfleet import errors

    for name, value in vars(errors).items():
        if isinstance(value, type) and issubclass(value, Exception):
            assert issubclass(value, armfleet.ArmfleetError), name


@pytest.mark.parametrize("method", ["spawn", "run", "step", "close"])
def test_world_methods(method: str) -> None:
    assert callable(getattr(armfleet.World, method))


@pytest.mark.parametrize("prop", ["tf", "bus", "time", "dt", "arms"])
def test_world_properties(prop: str) -> None:
    assert isinstance(inspect.getattr_static(armfleet.World, prop), property)


def test_world_signatures_match_the_readme() -> None:
    world_init = inspect.signature(armfleet.World)
    assert world_init.parameters["dt"].default == 0.001
    spawn = inspect.signature(armfleet.World.spawn)
    assert list(spawn.parameters)[:4] == ["self", "name", "model", "at"]
    assert spawn.parameters["model"].default == "panda"
    run = inspect.signature(armfleet.World.run)
    assert list(run.parameters)[:2] == ["self", "duration"]


@pytest.mark.parametrize("prop", ["joint_names", "joint_state", "is_moving"])
def test_arm_properties(prop: str) -> None:
    assert isinstance(inspect.getattr_static(armfleet.Arm, prop), property)


def test_arm_move_to() -> None:
    """One positional argument (issue #2's contract); planning options only by keyword (#16)."""
    parameters = inspect.signature(armfleet.Arm.move_to).parameters
    positional = [
        name for name, p in parameters.items() if p.kind is not inspect.Parameter.KEYWORD_ONLY
    ]
    assert positional == ["self", "positions"]
    assert {"avoid_collisions", "clearance_m", "timeout_s"} <= set(parameters)


def test_readme_contract_runs(world: armfleet.World) -> None:
    """The contract of issue #2, item 9, in a few lines (types, not tracking figures)."""
    bob = world.spawn("bob", model="panda", at=(0, 0))
    toby = world.spawn("toby", model="panda", at=(1, 0, 0, 180))
    assert isinstance(bob, armfleet.Arm) and isinstance(toby, armfleet.Arm)
    assert all(name.startswith("bob_") for name in bob.joint_names)
    heard: list[armfleet.JointState] = []
    world.bus.subscribe("/bob/joint_states", heard.append)
    bob.move_to(bob.positions + 0.05)
    assert bob.is_moving
    world.step()
    world.run(0.1)
    assert len(heard) == 101  # 1000 Hz, one step plus 0.1 s
    assert isinstance(bob.joint_state, armfleet.JointState)
    transform = world.tf.lookup("world", "bob_tool0")
    assert transform.shape == (4, 4)
    world.close()
    assert world.closed
