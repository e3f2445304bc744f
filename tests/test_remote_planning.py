"""Collision-free moves through the live API's Python client (issue 16): the keywords of the
local ``Arm``/``World``, a ``PlanningFailed`` raised again on the client with its reason
and the world's one line, and reply waits that leave room for the plan's time budget.

The world runs in another process (``armfleet spawn``, private runtime folder): bob, a
Panda at the origin, a static post 0.5 m in front of him and a static box away from both.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
import pytest

import armfleet
from armfleet.errors import ArmfleetError, InvalidFlag, InvalidNumber
from armfleet.planning import FailureReason, PlanningFailed
from armfleet.remote import Client, RemotePlanningFailed
from tests.remote_world import WorldProcess

#: A settled arm is this close to its target [rad].
HOLD_TOLERANCE_RAD = 2e-3
#: An arm that did not move stays this close to where it was [rad].
UNMOVED_RAD = 1e-3
#: A pose goal is reached this close [m] (the IK's and the controller's accuracy).
REACHED_M = 1e-3
POST = {"shape": "cylinder", "size": (0.04, 0.6), "at": (0.5, 0.0, 0.3)}
#: A box that swallows bob's hand when his joint 1 is at -0.9 rad (tool0 at about
#: (0.374, -0.471, 0.309) m, from the Panda's kinematics).
BOX = {"shape": "box", "size": (0.12, 0.12, 0.12), "at": (0.374, -0.471, 0.309)}
WAIT_S = 60.0


def tool_low(joint1: float) -> list[float]:
    """A Panda pose with the tool about 0.3 m over the floor, turned by joint1 [rad]."""
    return [joint1, 0.3, 0.0, -2.0, 0.0, 2.3, 0.785]


@dataclass
class Cell:
    world: WorldProcess
    client: Client


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Cell]:
    runtime = tmp_path_factory.mktemp("runtime")
    with (
        WorldProcess(runtime, "bob", "--at", "0,0", "--no-viewer", "--realtime") as world,
        armfleet.connect(world.address) as client,
    ):
        bob = client.arm("bob")
        bob.move_to(tool_low(0.9))
        bob.wait(WAIT_S)
        client.add_object("post", mass=0.0, **POST)  # type: ignore[arg-type]
        yield Cell(world, client)


def at_start(client: Client) -> None:
    """bob back at joint 1 = +0.9 (planned: the post may be between)."""
    bob = client.arm("bob")
    if np.abs(bob.positions - tool_low(0.9)).max() > HOLD_TOLERANCE_RAD:
        bob.move_to(tool_low(0.9), avoid_collisions=True)
        bob.wait(WAIT_S)


def test_a_planning_failure_is_a_planning_failed_with_the_worlds_line(cell: Cell) -> None:
    """The same request made in a local world with the same arm and objects fails with the
    same line: the client shows the world's words, and keeps the reason and the pair."""
    client = cell.client
    at_start(client)
    client.add_object("box", mass=0.0, **BOX)  # type: ignore[arg-type]
    try:
        bob = client.arm("bob")
        before = bob.positions
        with pytest.raises(RemotePlanningFailed) as caught:
            bob.move_to(tool_low(-0.9), avoid_collisions=True)
        error = caught.value
        assert isinstance(error, PlanningFailed)  # caught as the local one is
        assert error.reason is FailureReason.GOAL_IN_COLLISION
        assert error.arms == ("bob",)
        assert "box" in error.links and any(link.startswith("bob_") for link in error.links)
        assert error.kind == "PlanningFailed"
        assert "\n" not in str(error)
        with armfleet.World() as local:
            here = local.spawn("bob", model="panda", at=(0, 0), initial_positions=tool_low(0.9))
            local.add_object("post", mass=0.0, **POST)  # type: ignore[arg-type]
            local.add_object("box", mass=0.0, **BOX)  # type: ignore[arg-type]
            with pytest.raises(PlanningFailed) as expected:
                here.move_to(tool_low(-0.9), avoid_collisions=True)
        assert str(error) == str(expected.value)
        assert error.links == expected.value.links
        time.sleep(0.3)  # wall time in which a motion that got through would show
        assert np.abs(bob.positions - before).max() < UNMOVED_RAD
        assert bob.mode is armfleet.ArmMode.HOLDING
    finally:
        client.remove_object("box")


def test_a_pose_goal_is_planned_around_the_post(cell: Cell) -> None:
    client = cell.client
    at_start(client)
    bob = client.arm("bob")
    goal = np.array([0.4, -0.45, 0.3])  # beyond the post from where the tool is
    duration = bob.move_to_pose(goal, avoid_collisions=True, clearance_m=0.02, timeout_s=5.0)
    assert duration > 0.0
    bob.wait(WAIT_S)
    reached = client.lookup("world", "bob_tool0")[:3, 3]
    assert np.linalg.norm(reached - goal) < REACHED_M
    assert bob.mode is armfleet.ArmMode.HOLDING


def test_a_plan_longer_than_the_client_timeout_is_waited_for(cell: Cell) -> None:
    """A client whose timeout (0.05 s) is shorter than the plan still gets its answer: it
    waits its timeout plus the plan's budget, while the world's queue wait stays a share
    of its timeout alone. The plan builds the collision model of an arm spawned just
    before (carl, 1.5 m behind bob), which took 0.15-0.4 s here; a reply wait of the
    client's timeout alone gave up after 0.05 s while the world went on and moved bob."""
    client = cell.client
    at_start(client)
    client.spawn("carl", at=(-1.5, 0.0))
    try:
        with Client(cell.world.address) as hurried:
            bob = hurried.arm("bob")  # the handle, at the usual timeout (not what is tested)
            hurried.timeout = 0.05  # the plan's request: far shorter than the plan
            duration = bob.move_to(tool_low(-0.9), avoid_collisions=True, timeout_s=5.0)
        assert duration > 0.0
        bob = client.arm("bob")
        bob.wait(WAIT_S)
        assert np.abs(bob.positions - tool_low(-0.9)).max() < HOLD_TOLERANCE_RAD
    finally:
        client.remove("carl")


def test_a_budgeted_plan_goes_around_the_post_and_an_exhausted_one_names_its_budget(
    cell: Cell,
) -> None:
    """Over the live API, ``budget`` plans as locally: a budget of one iteration is
    refused in the world's line naming it, nothing moved; 400 get bob past the post."""
    client = cell.client
    at_start(client)
    bob = client.arm("bob")
    before = bob.positions
    with pytest.raises(RemotePlanningFailed) as caught:
        bob.move_to(tool_low(-0.9), avoid_collisions=True, budget=1)
    assert caught.value.reason is FailureReason.NO_PATH
    assert "a budget of 1 iterations" in str(caught.value) and "\n" not in str(caught.value)
    time.sleep(0.3)
    assert np.abs(bob.positions - before).max() < UNMOVED_RAD
    assert bob.move_to(tool_low(-0.9), avoid_collisions=True, budget=400) > 0.0
    bob.wait(WAIT_S)
    assert np.abs(bob.positions - tool_low(-0.9)).max() < HOLD_TOLERANCE_RAD


@pytest.mark.parametrize(
    ("keywords", "error", "says"),
    [
        pytest.param(
            {"avoid_collisions": "yes"},
            InvalidFlag,
            "avoid_collisions = 'yes' is invalid; give True or False",
            id="avoid_collisions='yes' -> InvalidFlag, nothing sent",
        ),
        pytest.param(
            {"avoid_collisions": True, "clearance_m": 0.0},
            InvalidNumber,
            "clearance_m = 0.0 is invalid; give metres in [0.001, 0.5]",
            id="clearance_m=0 -> InvalidNumber with the range, nothing sent",
        ),
        pytest.param(
            {"avoid_collisions": True, "clearance_m": float("nan")},
            InvalidNumber,
            "clearance_m = nan is invalid",
            id="clearance_m=nan -> InvalidNumber, nothing sent",
        ),
        pytest.param(
            {"avoid_collisions": True, "timeout_s": -1.0},
            InvalidNumber,
            "timeout_s = -1.0 is invalid; give seconds in [0.001, 60]",
            id="timeout_s=-1 -> InvalidNumber with the range, nothing sent",
        ),
        pytest.param(
            {"avoid_collisions": True, "budget": 0},
            InvalidNumber,
            "budget = 0 is invalid; give planner iterations, an integer in 1..1000000",
            id="budget=0 -> InvalidNumber with the range, nothing sent",
        ),
        pytest.param(
            {"avoid_collisions": True, "budget": 100, "timeout_s": 1.0},
            ArmfleetError,
            "give timeout_s (wall time) or budget (planner iterations, reproducible), not both",
            id="budget and timeout_s -> one or the other, nothing sent",
        ),
    ],
)
def test_the_client_refuses_bad_planning_options_as_the_local_api_does(
    cell: Cell, keywords: dict[str, object], error: type[Exception], says: str
) -> None:
    bob = cell.client.arm("bob")
    before = bob.positions
    far = before + 0.3
    moves: list[Callable[[], float]] = [
        lambda: bob.move_to(far, **keywords),  # type: ignore[arg-type]
        lambda: bob.move_to_pose((0.4, 0.0, 0.5), **keywords),  # type: ignore[arg-type]
        lambda: cell.client.move_together({"bob": far}, **keywords),  # type: ignore[arg-type]
    ]
    for move in moves:
        with pytest.raises(error) as caught:
            move()
        assert says in str(caught.value)
    with armfleet.World() as local:
        here = local.spawn("bob", model="panda", at=(0, 0), initial_positions=before)
        with pytest.raises(error) as expected:
            here.move_to(far, **keywords)  # type: ignore[arg-type]
    assert str(expected.value) == str(caught.value)  # the same words on both sides
    time.sleep(0.3)
    assert np.abs(bob.positions - before).max() < UNMOVED_RAD
