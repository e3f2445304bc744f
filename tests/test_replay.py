"""Replay without simulating: the recorded joint positions, at their times, into the viewer
(or a standalone HTML file)."""

from __future__ import annotations

import base64
import dataclasses
import json
import re
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import umsgpack

import armfleet
from armfleet.cli.main import main
from armfleet.description import ModelLibrary
from armfleet.messages import JointState
from armfleet.recording import ReplayPlayer, open_recording, replay_events
from armfleet.recording.replay import STILL_TOLERANCE, ReplayClock
from armfleet.recording.replay_arm import ReplayArm, usable_urdf
from armfleet.recording.replay_stream import ArmAppeared, JointPositions, TargetSent
from tests.conftest import RecordedRun


def recorded_states(run: RecordedRun, arm: str) -> list[tuple[int, JointState]]:
    """The joint states the world published, with their log times [ns]."""
    return [(t, m) for topic, t, m in run.messages if topic == f"/{arm}/joint_states"]


class FakeViewer:
    """Takes what a replay gives a viewer; notes each arm's joint positions at every tick."""

    def __init__(self) -> None:
        self.shown: dict[str, ReplayArm] = {}
        self.added: list[tuple[float, str]] = []
        self.ticks: list[tuple[float, dict[str, np.ndarray]]] = []
        self.clock: Any = None
        self.expected: list[dict[str, Any]] = []

    def expect_arms(self, positions: Any) -> None:
        self.expected.append(dict(positions))

    def add_arm(self, arm: Any) -> None:
        self.shown[arm.name] = arm
        self.added.append((self.clock.time if self.clock else -1.0, arm.name))

    def remove_arm(self, name: str) -> None:
        del self.shown[name]

    def tick(self, world: Any) -> None:
        self.clock = world
        positions = {name: arm.body.position.copy() for name, arm in self.shown.items()}
        self.ticks.append((world.time, positions))


def test_the_replay_stream_holds_every_recorded_position(recorded_run: RecordedRun) -> None:
    recording = open_recording(recorded_run.path)
    events = list(replay_events(recording))
    for arm in ("bob", "toby"):
        replayed = [e for e in events if isinstance(e, JointPositions) and e.arm == arm]
        live = recorded_states(recorded_run, arm)
        assert [e.time_ns for e in replayed] == [t for t, _ in live]
        for event, (_, state) in zip(replayed, live, strict=True):
            assert event.names == state.name
            assert event.positions == tuple(state.position.tolist())  # exactly
    appeared = [e for e in events if isinstance(e, ArmAppeared)]
    assert [e.arm.name for e in appeared] == ["bob", "toby"]
    (target,) = [e for e in events if isinstance(e, TargetSent)]
    assert target.arm == "bob" and target.positions == recorded_run.command
    times = [e.time_ns for e in events]
    assert times == sorted(times)


def test_a_thinned_stream_keeps_the_rate_and_the_last_state(recorded_run: RecordedRun) -> None:
    recording = open_recording(recorded_run.path)
    rate_hz = 60.0
    for arm in ("bob", "toby"):
        replayed = [
            e
            for e in replay_events(recording, rate_hz)
            if isinstance(e, JointPositions) and e.arm == arm
        ]
        live = dict(recorded_states(recorded_run, arm))
        gaps = np.diff([e.time_ns for e in replayed]) / 1e9
        assert np.all(gaps[:-1] >= 1 / rate_hz - 1e-9)
        assert len(replayed) == pytest.approx(2.0 * rate_hz, rel=0.1)
        assert replayed[-1].time_ns == max(live)  # the final pose is shown
        for event in replayed:
            assert event.positions == tuple(live[event.time_ns].position.tolist())


def test_the_player_shows_the_recorded_positions_at_their_times(
    recorded_run: RecordedRun,
) -> None:
    recording = open_recording(recorded_run.path)
    viewer = FakeViewer()
    duration = ReplayPlayer(recording, viewer, rate_hz=None).play(speed=None)
    start_s = (recording.start_ns or 0) / 1e9
    assert duration == pytest.approx(recording.duration_s)
    assert [name for _, name in viewer.added] == ["bob", "toby"]
    for arm in ("bob", "toby"):
        live = recorded_states(recorded_run, arm)
        first_s = live[0][0] / 1e9 - start_s
        shown: list[list[float]] = []  # each arm's positions, as they changed tick by tick
        for tick_time, positions in viewer.ticks:
            if arm not in positions:
                assert tick_time <= first_s + 1e-9  # not shown before its first state
            elif not shown or positions[arm].tolist() != shown[-1]:
                shown.append(positions[arm].tolist())
        recorded = [state.position.tolist() for _, state in live]
        # Every recorded state was on show, in order (toby holds still, so fewer changes).
        assert shown == [q for i, q in enumerate(recorded) if i == 0 or q != recorded[i - 1]]
    final = viewer.ticks[-1][1]["bob"]
    assert final.tolist() == recorded_states(recorded_run, "bob")[-1][1].position.tolist()


def test_replayed_arms_stand_where_they_were_spawned(recorded_run: RecordedRun) -> None:
    recording = open_recording(recorded_run.path)
    toby = ReplayArm(recording.arm("toby"), armfleet.Bus())
    toby.set_positions(*recorded_run.arms["toby"][1:], np.zeros(9))
    toby.kinematics.update(toby.body.position)
    expected = armfleet.SpawnPose(1.0, 0.0, 0.0, 180.0).matrix()
    assert toby.kinematics.world_pose("toby_base_link") == pytest.approx(expected, abs=1e-12)


def test_a_paced_replay_takes_the_recorded_time(recorded_run: RecordedRun) -> None:
    recording = open_recording(recorded_run.path)
    started = time.monotonic()
    ReplayPlayer(recording, FakeViewer()).play(speed=10.0)
    assert time.monotonic() - started >= recording.duration_s / 10.0 - 0.01


def replay_commands(path: Path) -> list[dict[str, Any]]:
    html = path.read_text(encoding="utf-8")
    match = re.search(r'<script [^>]*id="armfleet-commands">(.*?)</script>', html)
    assert match is not None
    return [umsgpack.unpackb(base64.b64decode(c)) for c in json.loads(match.group(1))]


def test_html_export_holds_the_recorded_motion(
    recorded_run: RecordedRun, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "replay.html"
    assert main(["replay", str(recorded_run.path), "--html", str(target)]) == 0
    assert capsys.readouterr().out == f"replay saved to {target}\n"
    html = target.read_text(encoding="utf-8")
    assert html.startswith("<!DOCTYPE html>") and "<script src" not in html  # standalone
    (animation,) = [c for c in replay_commands(target) if c["type"] == "set_animation"]
    clips = {entry["path"]: entry["clip"] for entry in animation["animations"]}
    tool0 = clips["/meshcat/armfleet/bob/landmarks/tool0"]
    position = next(track for track in tool0["tracks"] if track["name"] == ".position")
    # The last frame puts bob's flange where the last recorded joint state does.
    recording = open_recording(recorded_run.path)
    bob = ReplayArm(recording.arm("bob"), armfleet.Bus())
    last = recorded_states(recorded_run, "bob")[-1][1]
    bob.set_positions(last.name, last.position)
    bob.kinematics.update(bob.body.position)
    expected = bob.kinematics.world_pose("bob_tool0")[:3, 3]
    assert position["keys"][-1]["value"] == pytest.approx(expected, abs=1e-9)
    first = bob.kinematics.world_pose("bob_tool0")[:3, 3]
    assert np.linalg.norm(np.array(position["keys"][0]["value"]) - first) > 0.01  # it moved
    assert "/meshcat/armfleet/toby/landmarks/tool0" in clips


def test_live_replay_from_the_command_line(
    recorded_run: RecordedRun, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["replay", str(recorded_run.path), "--speed", "20", "--exit-at-end", "--no-wait"])
    out = capsys.readouterr().out.splitlines()
    assert code == 0
    assert re.fullmatch(r"viewer: http://127\.0\.0\.1:\d+/static/", out[0])
    duration = open_recording(recorded_run.path).duration_s
    assert out[1] == f"replaying {duration:.3f} s of bob, toby at 20x"
    assert out[2] == f"replay finished at t={duration:.3f}s"


def test_replay_needs_armfleet_arms(tmp_path: Path) -> None:
    path = tmp_path / "empty.mcap"
    with armfleet.World() as world:
        armfleet.record(world, path).stop()
    with pytest.raises(armfleet.RecordingError, match="no armfleet arm to replay"):
        ReplayPlayer(open_recording(path), FakeViewer())
    assert ReplayClock().time == 0.0


def elsewhere(urdf: str) -> str:
    """The URDF as recorded on another machine: its mesh paths are not here."""
    return urdf.replace('filename="/', 'filename="/another/machine/')


def test_an_arm_recorded_elsewhere_is_rebuilt_from_the_local_model(
    recorded_run: RecordedRun,
) -> None:
    bob = open_recording(recorded_run.path).arm("bob")
    moved = dataclasses.replace(bob, urdf=elsewhere(bob.urdf))
    assert usable_urdf(moved) == ModelLibrary().expand("panda", "bob_", bob.pose).urdf
    unknown = dataclasses.replace(moved, model="robot9000")
    with pytest.raises(armfleet.RecordingError, match=r"not on this machine.*'robot9000'"):
        usable_urdf(unknown)


def test_an_arm_that_cannot_be_rebuilt_is_skipped(recorded_run: RecordedRun) -> None:
    recording = open_recording(recorded_run.path)
    recording.arms = tuple(
        dataclasses.replace(arm, model="robot9000", urdf=elsewhere(arm.urdf))
        if arm.name == "toby"
        else arm
        for arm in recording.arms
    )
    viewer = FakeViewer()
    player = ReplayPlayer(recording, viewer)
    player.play(speed=None)
    assert [name for _, name in viewer.added] == ["bob"]
    assert "robot9000" in player.skipped["toby"]


def test_replay_needs_joint_states(tmp_path: Path) -> None:
    path = tmp_path / "no_states.mcap"
    with armfleet.World() as world:
        world.spawn("bob")
        armfleet.record(world, path, topics=["/tf_static"]).stop()
    with pytest.raises(armfleet.RecordingError, match="no /<arm>/joint_states messages"):
        ReplayPlayer(open_recording(path), FakeViewer())


def test_the_opening_is_shown_before_the_clock_starts(recorded_run: RecordedRun) -> None:
    """``on_opened`` is called once both arms came up standing still, before bob's target;
    the clock then starts there: at 1000x, paced, the rest takes recording / 1000."""
    recording = open_recording(recorded_run.path)
    viewer = FakeViewer()
    player = ReplayPlayer(recording, viewer)
    opened: list[tuple[float, list[str], int]] = []

    def on_opened() -> None:
        opened.append((player.clock.time, sorted(viewer.shown), len(viewer.ticks)))

    duration = player.play(speed=1000.0, on_opened=on_opened)
    assert duration == pytest.approx(recording.duration_s)
    [(time_s, shown, ticks)] = opened
    assert shown == ["bob", "toby"]
    # Before bob's target (the first thing that is not arms coming up), after toby's arrival.
    command_s = min(t for topic, t, _ in recorded_run.messages if topic.endswith("/commands"))
    toby_s = recorded_states(recorded_run, "toby")[0][0] / 1e9
    assert toby_s <= time_s < command_s / 1e9
    assert 0 < ticks < len(viewer.ticks)
    # Both arms were framed before they came, at their spawn positions, then no more.
    assert viewer.expected == [{"bob": (0.0, 0.0, 0.0), "toby": (1.0, 0.0, 0.0)}, {}]


def test_played_again_the_arms_stay_and_start_over(recorded_run: RecordedRun) -> None:
    """As ``--loop`` plays it: the second play keeps both arms (no second load), puts bob
    back at his first recorded state before the clock starts, and ends where he ended."""
    recording = open_recording(recorded_run.path)
    viewer = FakeViewer()
    player = ReplayPlayer(recording, viewer)
    player.play(speed=None, on_opened=lambda: None)
    states = recorded_states(recorded_run, "bob")
    at_opening: list[np.ndarray] = []
    duration = player.play(
        speed=None, on_opened=lambda: at_opening.append(player.arms["bob"].body.position.copy())
    )
    assert duration == pytest.approx(recording.duration_s)
    assert [name for _, name in viewer.added] == ["bob", "toby"]
    assert sorted(viewer.shown) == ["bob", "toby"]
    [position] = at_opening  # standing still: within the opening's tolerance of his start
    assert np.abs(position - states[0][1].position).max() <= STILL_TOLERANCE
    assert np.abs(position - states[-1][1].position).max() > 0.1
    assert viewer.ticks[-1][1]["bob"].tolist() == states[-1][1].position.tolist()
