"""Planning within a budget of iterations (``budget=``) instead of wall time.

The path is compared bit for bit between two processes, one of them planning while a
CPU burner runs and after a time-bounded plan that drew from OMPL's random numbers: what
a budget promises is that neither load nor history changes the plan. The exhausted
budget and the bad values are refused in one line, on the Python API (the CLI and the
live API refuse them with the same ranges: tests/test_cli_planning.py,
tests/test_remote_planning.py).

Run as a script (``python tests/test_planning_budget.py OUT.npy [--after-a-timed-plan]``),
this file is the worker process: it plans the shared cell's two-arm swap with
:data:`BUDGET` and saves the path.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet import FailureReason, PlanningFailed
from armfleet.errors import ArmfleetError, InvalidNumber

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run as a script: the tests package is found from the root
    sys.path.insert(0, str(ROOT))

from tests.planning_helpers import shared_cell, swap_goals  # noqa: E402

#: Iterations of the swap's plan: enough to find it (it needs tens), a small request.
BUDGET = 400
#: A worker planning the swap takes a few seconds; a hung one is a failure [s].
WORKER_TIMEOUT_S = 300.0


def plan_swap(out: Path, after_a_timed_plan: bool) -> None:
    """The worker: plan the swap with :data:`BUDGET` and save its waypoints to ``out``."""
    with shared_cell() as world:
        goals = swap_goals(world)
        if after_a_timed_plan:  # draws OMPL random numbers a fresh process has not drawn
            world.plan(goals, timeout_s=1.0)
        plan = world.plan(goals, budget=BUDGET)
        np.save(out, plan.waypoints)


def _worker(out: Path, *extra: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, str(Path(__file__)), str(out), *extra],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def _finish(worker: subprocess.Popen[bytes]) -> None:
    _, err = worker.communicate(timeout=WORKER_TIMEOUT_S)
    assert worker.returncode == 0, err.decode()


def test_the_same_budgeted_request_gives_the_same_path_under_load(tmp_path: Path) -> None:
    """Two processes plan the swap with the same budget: one alone, one while a CPU
    burner runs and after a timed plan; their paths are equal bit for bit (and the path
    is a search's, not the straight line)."""
    quiet, loaded = tmp_path / "quiet.npy", tmp_path / "loaded.npy"
    _finish(_worker(quiet))
    burner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        _finish(_worker(loaded, "--after-a-timed-plan"))
    finally:
        burner.kill()
        burner.wait()
    first, second = np.load(quiet), np.load(loaded)
    assert len(first) > 2, first  # searched: the straight swap hits the post
    assert first.shape == second.shape and first.tobytes() == second.tobytes()


def test_an_exhausted_budget_is_one_line_naming_it() -> None:
    with shared_cell() as world:
        goals = swap_goals(world)
        with pytest.raises(PlanningFailed) as failure:
            world.plan(goals, budget=1)
    message = str(failure.value)
    assert "\n" not in message and failure.value.reason is FailureReason.NO_PATH
    assert "a budget of 1 iterations" in message and "--budget" in message, message


@pytest.mark.parametrize(
    ("keywords", "error", "words"),
    [
        pytest.param({"budget": 0}, InvalidNumber, "integer in 1..1000000", id="budget 0"),
        pytest.param({"budget": 2.5}, InvalidNumber, "integer in 1..1000000", id="budget 2.5"),
        pytest.param({"budget": 10**7}, InvalidNumber, "integer in 1..1000000", id="1e7"),
        pytest.param({"budget": "many"}, InvalidNumber, "planner iterations", id="text"),
        pytest.param(
            {"budget": 10, "timeout_s": 1.0}, ArmfleetError, "not both", id="budget and timeout"
        ),
    ],
)
def test_a_bad_budget_is_refused_in_one_line(
    keywords: dict[str, object], error: type[Exception], words: str
) -> None:
    with armfleet.launch("shared_cell", viewer=False) as world:
        bob = world.arm("bob")
        for attempt in (
            lambda: bob.plan(bob.positions, **keywords),  # type: ignore[arg-type]
            lambda: bob.move_to(bob.positions, avoid_collisions=True, **keywords),  # type: ignore[arg-type]
        ):
            with pytest.raises(error) as refused:
                attempt()
            assert "\n" not in str(refused.value) and words in str(refused.value)
        with pytest.raises(ArmfleetError, match="go with avoid_collisions=True"):
            bob.move_to(bob.positions, budget=10)
        assert not bob.is_moving


if __name__ == "__main__":
    plan_swap(Path(sys.argv[1]), "--after-a-timed-plan" in sys.argv[2:])
