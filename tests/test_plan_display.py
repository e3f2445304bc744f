"""A planned motion in the viewer, in a recording and in the recording's replay (issue 16).

A collision-free plan announces itself on ``/<arm>/planned_motion`` as its motion
starts. Here :func:`tests.viewer_helpers.start_planned_move` does what the planner
does: it publishes a :class:`PlannedMotion` (a straight joint path whose tool path is
computed by Pinocchio in the test helpers, not by the viewer), then starts the motion.

The viewer side is checked at the protocol level, with a websocket client that gets
the very messages a page gets (:class:`SceneWatcher`); ``test_viewer_browser.py``
checks the line in a real page. Recordings are read back with the official ``mcap``
reader and validated with ``jsonschema``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import jsonschema  # type: ignore[import-untyped]
import numpy as np
import pytest
from mcap.reader import make_reader

import armfleet
from armfleet.messages import JointCommand, PlannedMotion
from armfleet.recording import open_recording
from armfleet.recording.encode import planned_motion
from armfleet.recording.replay import ReplayPlayer, start_replay_viewer
from armfleet.recording.replay_stream import PlanStarted, replay_events
from armfleet.viewer import Viewer
from armfleet.viewer.plan_lines import MAX_LINE_POINTS, PLAN_COLOR
from armfleet.viewer.scene import BACKGROUND_BOTTOM, BACKGROUND_TOP, GRID_COLOR
from tests.viewer_helpers import (
    SceneState,
    SceneWatcher,
    bob_and_toby_viewed,
    line_vertices,
    start_planned_move,
    straight_plan,
    tool0_pose,
)

#: The page gets float32 vertices: coordinates of ~1 m are within 1e-6 m.
VERTEX_TOLERANCE_M = 1e-6
#: trajectory_msgs/msg/JointTrajectoryPoint fields, in rosidl order.
POINT_FIELDS = ("positions", "velocities", "accelerations", "effort", "time_from_start")


def line_path(arm: str) -> str:
    return f"/meshcat/armfleet/{arm}/planned_motion"


def viewer_of(world: armfleet.World) -> Viewer:
    assert isinstance(world.viewer, Viewer), world.viewer_error
    return world.viewer


def nudge(arm: armfleet.Arm, delta: float) -> np.ndarray:
    """A target ``delta`` rad from the arm's home on every joint, 0.1 rad inside the limits
    (from home, not from where the arm is: a run of tests does not fold it onto itself)."""
    lower, upper = arm.joint_limits
    home = np.array(arm.description.home, dtype=float)
    target: np.ndarray = np.clip(home + delta, lower + 0.1, upper - 0.1)
    return target


def settle(world: armfleet.World, arm: armfleet.Arm, limit_s: float = 10.0) -> None:
    while arm.is_moving and limit_s > 0:
        world.run(0.05)
        limit_s -= 0.05
    world.run(0.05)


def color_distance(color: int, rgb: tuple[float, float, float]) -> int:
    """Largest channel difference [0, 255] between a hex colour and an RGB in [0, 1]."""
    channels = ((color >> 16) & 255, (color >> 8) & 255, color & 255)
    return max(abs(c - round(255 * v)) for c, v in zip(channels, rgb, strict=True))


@pytest.fixture(scope="module")
def viewed() -> Iterator[armfleet.World]:
    """A world with a viewer, bob at (0, 0) and toby at (1, 0)."""
    with bob_and_toby_viewed() as world:
        yield world


# -- the viewer ------------------------------------------------------------------------
@contextlib.contextmanager
def announcements(world: armfleet.World, arm: str) -> Iterator[list[PlannedMotion]]:
    """The plans published on ``/<arm>/planned_motion`` while in the block."""
    seen: list[PlannedMotion] = []
    subscription = world.bus.subscribe(f"/{arm}/planned_motion", seen.append)
    try:
        yield seen
    finally:
        subscription.cancel()


def test_a_collision_free_move_shows_its_path_while_it_runs(viewed: armfleet.World) -> None:
    """The planner's own announcement (``avoid_collisions=True``), drawn and removed."""
    world, bob = viewed, viewed.arm("bob")
    viewer = viewer_of(world)
    with SceneWatcher(viewer.port) as watcher, announcements(world, "bob") as announced:
        watcher.wait_quiet()
        goal = nudge(bob, 0.4)
        start_pose = tool0_pose(bob)
        duration = bob.move_to(goal, avoid_collisions=True)
        world.step()
        [plan] = announced
        watcher.wait_for(lambda scene: line_path("bob") in scene.objects)
        command = watcher.state.objects[line_path("bob")]
        assert command["object"]["object"]["type"] == "Line"
        vertices = line_vertices(command)
        np.testing.assert_allclose(vertices, plan.tool_path, atol=VERTEX_TOLERANCE_M)
        # The path runs from where tool0 is to where it will be (Pinocchio, independently).
        np.testing.assert_allclose(vertices[0], start_pose[:3, 3], atol=VERTEX_TOLERANCE_M)
        goal_pose = tool0_pose(bob, goal)
        np.testing.assert_allclose(vertices[-1], goal_pose[:3, 3], atol=VERTEX_TOLERANCE_M)
        assert line_path("toby") not in watcher.state.objects, "toby has no plan"

        # Shown at every step while bob moves; gone at the first step he stands still.
        while bob.is_moving:
            assert "bob" in viewer.planned_motions, f"line gone at t = {world.time:.3f} s"
            world.step()
        assert "bob" not in viewer.planned_motions
        assert world.time <= plan.stamp + duration + 2 * world.dt, "gone as the motion ended"
        watcher.wait_for(lambda scene: line_path("bob") not in scene.objects)
        # Its node is gone, the arm's meshes are all still there.
        assert len(watcher.state.nodes_under("/meshcat/armfleet/bob/visuals")) == 11
    assert viewer.error is None


def test_a_plan_published_by_hand_is_drawn_the_same_way(viewed: armfleet.World) -> None:
    """What the planner does, done by hand (publish, then an ordinary move): the line is
    the published tool path, until the motion ends."""
    world, bob = viewed, viewed.arm("bob")
    viewer = viewer_of(world)
    with SceneWatcher(viewer.port) as watcher:
        watcher.wait_quiet()
        plan = start_planned_move(world, bob, nudge(bob, -0.3))
        world.step()
        watcher.wait_for(lambda scene: line_path("bob") in scene.objects)
        vertices = line_vertices(watcher.state.objects[line_path("bob")])
        np.testing.assert_allclose(vertices, plan.tool_path, atol=VERTEX_TOLERANCE_M)
        while bob.is_moving:
            assert "bob" in viewer.planned_motions, f"line gone at t = {world.time:.3f} s"
            world.step()
        assert "bob" not in viewer.planned_motions
        watcher.wait_for(lambda scene: line_path("bob") not in scene.objects)


def test_the_line_is_a_visible_colour(viewed: armfleet.World) -> None:
    world, bob = viewed, viewed.arm("bob")
    with SceneWatcher(viewer_of(world).port) as watcher:
        watcher.wait_quiet()
        start_planned_move(world, bob, nudge(bob, 0.2))
        world.step()
        watcher.wait_for(lambda scene: line_path("bob") in scene.objects)
        material = watcher.state.objects[line_path("bob")]["object"]["materials"][0]
        settle(world, bob)
    assert material["type"] == "LineBasicMaterial" and material["color"] == PLAN_COLOR
    assert material["opacity"] == 1.0 and not material["transparent"]
    for background in (BACKGROUND_TOP, BACKGROUND_BOTTOM):
        assert color_distance(material["color"], background) > 100, "stands out of the sky"
    grid = ((GRID_COLOR >> 16) / 255, ((GRID_COLOR >> 8) & 255) / 255, (GRID_COLOR & 255) / 255)
    assert color_distance(material["color"], grid) > 100, "stands out of the grid"


def test_re_targeting_mid_motion_removes_the_line(viewed: armfleet.World) -> None:
    world, bob = viewed, viewed.arm("bob")
    viewer = viewer_of(world)
    with SceneWatcher(viewer.port) as watcher, announcements(world, "bob") as announced:
        watcher.wait_quiet()
        bob.move_to(nudge(bob, 0.4), avoid_collisions=True)
        world.run(0.1)
        assert "bob" in viewer.planned_motions
        # The plan's own target again (as the planner publishes "for the record") keeps it.
        own = JointCommand(tuple(bob_goal(announced[0])))
        world.bus.publish("/bob/position_controller/commands", own)
        world.step()
        assert "bob" in viewer.planned_motions
        bob.move_to(nudge(bob, -0.2))  # a new target: the plan is abandoned
        world.step()
        assert "bob" not in viewer.planned_motions
        assert bob.is_moving, "the arm goes on, to its new target"
        watcher.wait_for(lambda scene: line_path("bob") not in scene.objects)
        settle(world, bob)
    assert viewer.error is None


def bob_goal(plan: PlannedMotion) -> list[float]:
    goal: list[float] = np.asarray(plan.positions)[-1].tolist()
    return goal


def test_a_new_plan_replaces_the_line(viewed: armfleet.World) -> None:
    world, bob, toby = viewed, viewed.arm("bob"), viewed.arm("toby")
    viewer = viewer_of(world)
    with SceneWatcher(viewer.port) as watcher:
        watcher.wait_quiet()
        start_planned_move(world, bob, nudge(bob, 0.4))
        toby_plan = start_planned_move(world, toby, nudge(toby, 0.3))
        world.run(0.1)
        second = start_planned_move(world, bob, nudge(bob, -0.2))
        world.step()
        assert viewer.planned_motions["bob"] is second
        assert viewer.planned_motions["toby"] is toby_plan, "toby's line is his own"

        def shows_second(scene: SceneState) -> bool:
            command = scene.objects.get(line_path("bob"))
            return command is not None and np.allclose(
                line_vertices(command), second.tool_path, atol=VERTEX_TOLERANCE_M
            )

        watcher.wait_for(shows_second)
        settle(world, bob)
        settle(world, toby)
        watcher.wait_for(lambda scene: not scene.nodes_under("/meshcat/armfleet/bob/planned"))
        # toby's delete is sent on its own: wait for it too (asserting at once raced it).
        watcher.wait_for(lambda scene: line_path("toby") not in scene.objects)
    assert viewer.planned_motions == {}


def test_a_long_path_is_thinned_with_both_ends_kept(viewed: armfleet.World) -> None:
    world, bob = viewed, viewed.arm("bob")
    with SceneWatcher(viewer_of(world).port) as watcher:
        watcher.wait_quiet()
        goal = nudge(bob, 0.3)
        plan = straight_plan(world, bob, goal, waypoints=3 * MAX_LINE_POINTS + 7)
        world.bus.publish("/bob/planned_motion", plan)
        bob.move_to(goal)
        world.step()
        watcher.wait_for(lambda scene: line_path("bob") in scene.objects)
        vertices = line_vertices(watcher.state.objects[line_path("bob")])
        settle(world, bob)
    assert len(vertices) == MAX_LINE_POINTS
    np.testing.assert_allclose(vertices[[0, -1]], plan.tool_path[[0, -1]], atol=1e-6)


def bad_plan(**change: Any) -> Any:
    """A function making, from a good plan, one with ``change`` applied."""

    def make(plan: PlannedMotion) -> PlannedMotion:
        values = {key: value(plan) if callable(value) else value for key, value in change.items()}
        return dataclasses.replace(plan, **values)

    return make


def row_is(array: Any, row: int) -> Any:
    """A column of booleans: True at ``row`` of ``array``."""
    return np.arange(len(array))[:, None] == row


BAD_PLANS = [
    pytest.param(
        bad_plan(tool_path=lambda p: np.where(row_is(p.tool_path, 3), np.nan, p.tool_path)),
        id="a NaN in the tool path -> no line, a warning, the motion and the viewer go on",
    ),
    pytest.param(
        bad_plan(tool_path=lambda p: p.tool_path[:, :2]),
        id="a tool path of 2-D points -> no line, a warning, the motion and the viewer go on",
    ),
    pytest.param(
        bad_plan(tool_path=lambda p: p.tool_path[:1]),
        id="a tool path of one point -> no line, a warning, the motion and the viewer go on",
    ),
    pytest.param(
        bad_plan(tool_path="a line"),
        id="text for the tool path -> no line, a warning, the motion and the viewer go on",
    ),
]


@pytest.mark.parametrize("spoil", BAD_PLANS)
def test_an_undrawable_plan_is_not_drawn_and_hurts_nothing(
    viewed: armfleet.World, spoil: Any, caplog: pytest.LogCaptureFixture
) -> None:
    world, bob = viewed, viewed.arm("bob")
    viewer = viewer_of(world)
    goal = nudge(bob, 0.25)
    plan = spoil(straight_plan(world, bob, goal))
    with caplog.at_level(logging.WARNING, logger="armfleet"):
        world.bus.publish("/bob/planned_motion", plan)
        bob.move_to(goal)
        world.run(0.1)
    assert "bob" not in viewer.planned_motions
    assert "bob's planned motion has no drawable tool path" in caplog.text
    assert bob.is_moving and viewer.error is None
    settle(world, bob)
    np.testing.assert_allclose(bob.positions, goal, atol=1e-3)  # the holding tolerance
    # And a good plan after it is drawn.
    start_planned_move(world, bob, nudge(bob, -0.25))
    world.step()
    assert "bob" in viewer.planned_motions
    settle(world, bob)
    assert viewer.error is None


def test_a_protective_stop_and_the_arms_removal_take_the_line_away() -> None:
    """bob's planned path runs into a wall: the stop removes the line at once (the arm
    still brakes); then a plan is under way as bob is removed."""
    with armfleet.World(viewer=True) as world:
        viewer = viewer_of(world)
        bob = world.spawn("bob", at=(0, 0))
        world.add_object("wall", "box", size=(0.1, 1.0, 1.0), mass=0, at=(0.55, 0, 0.5))
        home = bob.positions
        goal = home.copy()
        goal[1] += 1.0  # shoulder forward
        goal[3] += 1.2  # elbow open: tool0 goes through the wall
        with SceneWatcher(viewer.port) as watcher:
            watcher.wait_quiet()
            start_planned_move(world, bob, goal)
            world.step()
            assert "bob" in viewer.planned_motions
            while bob.mode != armfleet.ArmMode.PROTECTIVE_STOP and world.time < 5.0:
                world.step()
            assert bob.mode == armfleet.ArmMode.PROTECTIVE_STOP, "bob touched the wall"
            world.step()
            assert "bob" not in viewer.planned_motions
            watcher.wait_for(lambda scene: line_path("bob") not in scene.objects)

            world.run(0.5)  # braked
            bob.reset_stop()
            start_planned_move(world, bob, home)  # back, away from the wall
            world.step()
            watcher.wait_for(lambda scene: line_path("bob") in scene.objects)
            world.remove("bob")
            watcher.wait_for(lambda scene: not scene.nodes_under("/meshcat/armfleet/bob"))
            world.run(0.1)
        assert viewer.planned_motions == {} and viewer.error is None


# -- recording ---------------------------------------------------------------------------
def plans_recorded(path: Path) -> tuple[dict[str, Any], dict[str, list[tuple[int, Any]]]]:
    """(schema by topic, (log time [ns], message) by topic) of the planned-motion channels,
    from the official ``mcap`` reader."""
    schemas: dict[str, Any] = {}
    messages: dict[str, list[tuple[int, Any]]] = {}
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        for channel in summary.channels.values():
            if channel.topic.endswith("/planned_motion"):
                record = summary.schemas[channel.schema_id]
                assert record.encoding == "jsonschema" and channel.message_encoding == "json"
                assert record.name == "armfleet_msgs/msg/PlannedMotion"
                schemas[channel.topic] = json.loads(record.data)
                messages[channel.topic] = []
        for _, channel, message in reader.iter_messages(topics=list(schemas)):
            messages[channel.topic].append((message.log_time, json.loads(message.data)))
    return schemas, messages


def record_planned_move(path: Path) -> tuple[PlannedMotion, float]:
    """Record bob running one collision-free motion to its end; (its plan as announced, the
    recording's end [s])."""
    with armfleet.World() as world:
        bob = world.spawn("bob", at=(0, 0))
        world.spawn("toby", at=(1, 0))
        with armfleet.record(world, path), announcements(world, "bob") as announced:
            world.run(0.05)
            bob.move_to(nudge(bob, 0.4), avoid_collisions=True)
            settle(world, bob)
            world.run(0.3)
            [plan] = announced
            return plan, world.time


@pytest.fixture(scope="module")
def recorded_plan(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, PlannedMotion, float]:
    path = tmp_path_factory.mktemp("plan") / "plan.mcap"
    plan, end_s = record_planned_move(path)
    return path, plan, end_s


def test_a_recorded_plan_fits_its_schema_and_reads_back_exactly(
    recorded_plan: tuple[Path, PlannedMotion, float],
) -> None:
    path, plan, _ = recorded_plan
    schemas, messages = plans_recorded(path)
    assert messages["/toby/planned_motion"] == [], "toby planned nothing"
    schema = schemas["/bob/planned_motion"]
    jsonschema.Draft202012Validator.check_schema(schema)
    [(log_time, message)] = messages["/bob/planned_motion"]
    errors = list(jsonschema.Draft202012Validator(schema).iter_errors(message))
    assert not errors, f"{errors[0].message} at {list(errors[0].path)}"
    assert log_time == round(plan.stamp * 1e9), "logged when the motion starts"
    # The joint path is a whole ROS trajectory_msgs/msg/JointTrajectory.
    trajectory = message["trajectory"]
    assert tuple(trajectory) == ("header", "joint_names", "points")
    assert trajectory["joint_names"] == list(plan.name)
    assert all(tuple(point) == POINT_FIELDS for point in trajectory["points"])
    assert message["header"]["frame_id"] == "world"
    back = planned_motion(message)
    assert back.stamp == pytest.approx(plan.stamp, abs=1e-9)
    assert back.name == plan.name
    np.testing.assert_allclose(back.time_from_start, plan.time_from_start, atol=1e-9)
    np.testing.assert_array_equal(back.positions, plan.positions)  # 17 digits: exact
    np.testing.assert_array_equal(back.tool_path, plan.tool_path)
    assert back.duration == pytest.approx(plan.duration, abs=1e-9)


NON_FINITE_PLANS = [
    pytest.param(
        {"positions": lambda p: np.where(row_is(p.positions, 2), np.nan, p.positions)},
        lambda m: [len(pt["positions"]) for pt in m["trajectory"]["points"]][2] == 0,
        id="a NaN waypoint -> recorded with that waypoint's positions empty (ROS: n/a)",
    ),
    pytest.param(
        {"time_from_start": lambda p: (*p.time_from_start[:-1], math.inf)},
        lambda m: len(m["trajectory"]["points"]) == 24,
        id="an infinite waypoint time -> recorded without that waypoint",
    ),
    pytest.param(
        {"tool_path": lambda p: p.tool_path * np.inf},
        lambda m: m["tool_path"] == [],
        id="an infinite tool path -> recorded with the tool path empty (n/a)",
    ),
]


@pytest.mark.parametrize(("change", "written"), NON_FINITE_PLANS)
def test_non_finite_plans_are_recorded_within_the_schema(
    tmp_path: Path, change: dict[str, Any], written: Any
) -> None:
    path = tmp_path / "odd.mcap"
    with armfleet.World() as world:
        bob = world.spawn("bob", at=(0, 0))
        with armfleet.record(world, path):
            plan = straight_plan(world, bob, nudge(bob, 0.2))
            world.bus.publish("/bob/planned_motion", bad_plan(**change)(plan))
            world.step()
    schemas, messages = plans_recorded(path)
    [(_, message)] = messages["/bob/planned_motion"]
    validator = jsonschema.Draft202012Validator(schemas["/bob/planned_motion"])
    errors = list(validator.iter_errors(message))
    assert not errors, f"{errors[0].message} at {list(errors[0].path)}"
    assert written(message)


@pytest.mark.parametrize(
    "stamp",
    [
        pytest.param(
            math.nan,
            id="a NaN stamp -> that plan is not recorded, one warning, the recording goes on",
        )
    ],
)
def test_a_plan_with_no_time_is_skipped_by_the_recorder_and_nothing_else_is(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, stamp: float
) -> None:
    """A stamp that is not finite cannot be written (a header holds integers): that one
    message is left out with one warning; the plans around it and every other topic are
    recorded."""
    path = tmp_path / "no_time.mcap"
    with armfleet.World() as world:
        bob = world.spawn("bob", at=(0, 0))
        with armfleet.record(world, path), caplog.at_level(logging.WARNING, logger="armfleet"):
            plan = straight_plan(world, bob, nudge(bob, 0.2))
            world.bus.publish("/bob/planned_motion", plan)
            world.bus.publish("/bob/planned_motion", dataclasses.replace(plan, stamp=stamp))
            world.bus.publish("/bob/planned_motion", plan)
            world.run(0.01)
    assert "cannot encode a message of /bob/planned_motion" in caplog.text
    _, messages = plans_recorded(path)
    assert len(messages["/bob/planned_motion"]) == 2
    states = open_recording(path).topics["/bob/joint_states"]
    assert states.message_count >= 10, "the recording went on"


# -- replay ------------------------------------------------------------------------------
def test_the_replay_stream_has_the_plan_at_its_time(
    recorded_plan: tuple[Path, PlannedMotion, float],
) -> None:
    path, plan, _ = recorded_plan
    plans = [e for e in replay_events(open_recording(path)) if isinstance(e, PlanStarted)]
    [event] = plans
    assert event.arm == "bob" and event.time_ns == round(plan.stamp * 1e9)
    np.testing.assert_array_equal(event.plan.tool_path, plan.tool_path)


def test_the_replay_draws_the_planned_path_until_the_motion_ends(
    recorded_plan: tuple[Path, PlannedMotion, float],
) -> None:
    path, plan, end_s = recorded_plan
    viewer = start_replay_viewer()
    seen: list[tuple[float, bool]] = []
    try:
        recording = open_recording(path)
        start_s = (recording.start_ns or 0) / 1e9
        with SceneWatcher(viewer.port) as watcher:
            player = ReplayPlayer(recording, viewer, rate_hz=200.0)
            player.play(
                speed=None, on_event=lambda t: seen.append((t, "bob" in viewer.planned_motions))
            )
            scene = watcher.wait_quiet()
        drawn = [kind for kind, where in scene.log if where == line_path("bob")]
        assert drawn == ["set_object", "delete"], "drawn once, removed once"
    finally:
        viewer.close()
    begins, ends = plan.stamp - start_s, plan.stamp + plan.duration - start_s
    shown = [t for t, on in seen if on]
    assert shown, "the line was drawn"
    assert min(shown) == pytest.approx(begins, abs=1e-6), "from the plan's start"
    # Until the motion's end; the replay knows the arm stopped from /bob/status (10 Hz).
    assert max(shown) < ends
    during = [on for t, on in seen if begins <= t < ends - 0.1]
    assert during and all(during), "on show through the motion"
    assert not any(on for t, on in seen if t >= ends)
    assert seen[-1][0] == pytest.approx(end_s - start_s, abs=0.01)
