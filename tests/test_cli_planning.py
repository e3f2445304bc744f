"""``armfleet move ... --avoid-collisions`` and ``armfleet move-together ... --avoid-collisions``
as a user runs them (issue 16): real subprocesses against a world running in another
process, in a private runtime folder.

The scene: Pandas with their tool low over the floor, on one side of a static post; the
goal is the same pose mirrored to the other side. A straight joint motion sweeps the arm
through the post (each test proves it, after the planned motion, by sending the straight
motion back: it ends in a protective stop on the post, and /collisions reports it). The
planned motion must arrive (positions read back from the world) with no contact on
/collisions while it runs and no protective stop.
"""

from __future__ import annotations

import re
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

import armfleet
from armfleet.messages import CollisionReport, JointState
from armfleet.remote import Client
from armfleet.services.protocol import MAX_QUEUE_SIZE
from tests.remote_world import WorldProcess, cli, wait_until

#: A settled arm is this close to its target [rad] (the CLI tests' holding figure).
HOLD_TOLERANCE_RAD = 2e-3
#: An arm that did not move stays this close to where it was [rad] (its hold tolerance).
UNMOVED_RAD = 1e-3
#: Bob's base, and toby's facing him 0.9 m away (the shared cell's spacing).
BOB_AT, TOBY_AT = "0,0", "0.9,0,0,180"


def tool_low(joint1: float) -> list[float]:
    """A Panda pose with the tool about 0.3 m over the floor, 0.6 m out, turned by joint1
    [rad]: +0.9 puts bob's tool at y = +0.47 m, -0.9 at y = -0.47 m."""
    return [joint1, 0.3, 0.0, -2.0, 0.0, 2.3, 0.785]


def joints(values: list[float]) -> list[str]:
    return [f"{v:g}" for v in values]


@dataclass
class Watch:
    """What the world published while a test ran: every contact, and bob's latest state."""

    contacts: list[tuple[float, str, str]] = field(default_factory=list)
    latest: dict[str, float] = field(default_factory=dict)

    def on_collisions(self, report: CollisionReport) -> None:
        self.contacts.extend((report.stamp, c.link_a or c.body_a, c.link_b or c.body_b)
                             for c in report.contacts)  # fmt: skip

    def on_state(self, state: JointState) -> None:
        self.latest["stamp"] = state.stamp

    def caught_up(self, client: Client) -> None:
        """Wait until the stream has delivered a state published after now in the world, so
        that every contact report of the steps before it has been delivered too (the
        world's queues are filled in step order and flushed every 2 ms)."""
        now = client.info().time_s
        assert wait_until(lambda: self.latest.get("stamp", -1.0) > now + 0.05, timeout=30.0)


def watch(client: Client) -> Watch:
    seen = Watch()
    client.subscribe("/collisions", seen.on_collisions, queue_size=MAX_QUEUE_SIZE)
    client.subscribe("/bob/joint_states", seen.on_state, rate_hz=50.0)
    return seen


def ok(runtime: Path, *args: str) -> str:
    """Run ``armfleet ARGS``; it must succeed; its one output line."""
    result = cli(runtime, *args)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    (line,) = result.stdout.splitlines()
    return line


def refused(result: subprocess.CompletedProcess[str]) -> str:
    """The one error line of a command that must fail as a user error."""
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "Traceback" not in result.stderr
    assert result.stdout == ""
    (line,) = result.stderr.splitlines()
    assert line.startswith("armfleet: error: ")
    return line


def add_post(client: Client) -> None:
    """A static post 0.6 m tall, 4 cm in radius, 0.5 m in front of bob (toby's tool at rest
    at 0.9 m is clear of it)."""
    client.add_object("post", "cylinder", size=(0.04, 0.6), mass=0.0, at=(0.5, 0.0, 0.3))


def straight_back_hits_the_post(
    runtime: Path, seen: Watch, client: Client, start: list[float], *names: str
) -> None:
    """The straight motion back to ``start`` stops on the post: the planned path was not
    the straight one, and contacts, had there been any, would have been seen."""
    seen.contacts.clear()
    targets = [f"{name}={','.join(joints(start))}" for name in names]
    result = cli(runtime, "move-together", *targets, "--wait")
    line = refused(result)
    assert "protective stop" in line and "post" in line, line
    seen.caught_up(client)
    assert any("post" in (a, b) for _, a, b in seen.contacts), seen.contacts[:3]


@pytest.fixture
def bob_world(tmp_path: Path) -> Iterator[WorldProcess]:
    with WorldProcess(tmp_path, "bob", "--at", BOB_AT, "--no-viewer", "--realtime") as world:
        yield world


def test_move_avoid_collisions_goes_around_the_post(bob_world: WorldProcess) -> None:
    runtime = bob_world.runtime_dir
    start, goal = tool_low(0.9), tool_low(-0.9)
    ok(runtime, "move", "bob", "--joints", *joints(start), "--wait")
    with armfleet.connect(bob_world.address) as client:
        add_post(client)
        seen = watch(client)
        line = ok(runtime, "move", "bob", "--joints", *joints(goal), "--avoid-collisions", "--wait")
        assert line.startswith("bob: holding [-0.900 +0.300"), line
        seen.caught_up(client)
        assert seen.contacts == []
        bob = client.arm("bob")
        assert bob.mode is armfleet.ArmMode.HOLDING
        assert np.abs(bob.positions - goal).max() < HOLD_TOLERANCE_RAD
        straight_back_hits_the_post(runtime, seen, client, start, "bob")


def test_a_goal_in_collision_is_one_line_and_nothing_moves(bob_world: WorldProcess) -> None:
    runtime = bob_world.runtime_dir
    start = tool_low(0.9)
    ok(runtime, "move", "bob", "--joints", *joints(start), "--wait")
    with armfleet.connect(bob_world.address) as client:
        # Where tool0 is at the goal, read from the world with bob there (then back).
        ok(runtime, "move", "bob", "--joints", *joints(tool_low(-0.9)), "--wait")
        tool = client.lookup("world", "bob_tool0")[:3, 3]
        ok(runtime, "move", "bob", "--joints", *joints(start), "--wait")
        client.add_object("box", "box", size=(0.12, 0.12, 0.12), mass=0.0, at=tuple(tool))
        seen = watch(client)
        before = client.arm("bob").positions
        pattern = re.compile(
            r"^armfleet: error: cannot plan bob: goal in collision: (?P<a>\S+) "
            r"(touches|is [0-9.]+ mm from) (?P<b>\S+) \(clearance 10 mm"
            r"( \+ [0-9.]+ mm of the physics' collision margin)?\)$"
        )
        for goal in (
            ["--joints", *joints(tool_low(-0.9))],
            ["--pose", *joints(list(tool))],  # keeping the tool's orientation: IK, same box
        ):
            line = refused(cli(runtime, "move", "bob", *goal, "--avoid-collisions", "--wait"))
            match = pattern.match(line)
            assert match, line
            assert {match["a"], match["b"]} & {"box"}, line
            assert any(name.startswith("bob_") for name in (match["a"], match["b"])), line
        time.sleep(0.3)  # wall time in which a motion that got through would show
        seen.caught_up(client)
        bob = client.arm("bob")
        assert bob.mode is armfleet.ArmMode.HOLDING
        assert np.abs(bob.positions - before).max() < UNMOVED_RAD
        assert seen.contacts == []


def test_move_together_avoid_collisions_swaps_two_arms_across_the_post(tmp_path: Path) -> None:
    """bob's tool goes from +y to -y and toby's from -y to +y (toby faces bob), past a post
    between them: straight, both would sweep through the post at once."""
    with WorldProcess(
        tmp_path, "bob", "toby", "--at", BOB_AT, TOBY_AT, "--no-viewer", "--realtime"
    ) as world:
        runtime = world.runtime_dir
        start, goal = tool_low(0.7), tool_low(-0.7)
        there = [f"bob={','.join(joints(start))}", f"toby={','.join(joints(start))}"]
        ok(runtime, "move-together", *there, "--wait")
        with armfleet.connect(world.address) as client:
            client.add_object("post", "cylinder", size=(0.04, 0.6), mass=0.0, at=(0.45, 0, 0.3))
            seen = watch(client)
            back = [f"bob={','.join(joints(goal))}", f"toby={','.join(joints(goal))}"]
            line = ok(runtime, "move-together", *back, "--avoid-collisions", "--wait")
            assert line.startswith("bob, toby: moved together in "), line
            seen.caught_up(client)
            assert seen.contacts == []
            for name in ("bob", "toby"):
                arm = client.arm(name)
                assert arm.mode is armfleet.ArmMode.HOLDING, name
                assert np.abs(arm.positions - goal).max() < HOLD_TOLERANCE_RAD, name
            straight_back_hits_the_post(runtime, seen, client, start, "bob", "toby")
