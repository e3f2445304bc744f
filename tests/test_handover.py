"""examples/handover.py: bob picks the bar, toby takes it mid-air and puts it down."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "handover.py"


@pytest.fixture(scope="module")
def handover() -> ModuleType:
    spec = importlib.util.spec_from_file_location("handover_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("seed", [0, 3])
def test_bar_changes_hands_and_lands_on_the_mat(handover: ModuleType, seed: int) -> None:
    outcome = handover.run(seed)  # seed 3: the bar starts moved by up to 2 cm and 10 deg
    assert outcome.picked  # bob held it after closing on it
    assert outcome.error_m < 0.02  # the bar ends within 2 cm of its target
    assert outcome.steps_unheld == 0  # from pick to place, always in at least one gripper
    assert outcome.arm_contacts == 0  # bob and toby never touched
    assert outcome.stops == 0  # no protective stop: the bar and the grippers are allowed
    assert outcome.success
