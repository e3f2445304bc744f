"""Shared fixtures: DIRECT-mode worlds, a bob/toby pair, the model library."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

import armfleet
from armfleet.description import ModelLibrary


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
