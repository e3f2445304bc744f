"""Recording to MCAP: every topic, at its rate, valid JSON under valid JSON Schemas, read back
with the ``mcap`` library itself; arms coming and going; a crash-safe file."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

import jsonschema  # type: ignore[import-untyped]
import numpy as np
import pytest
from mcap.reader import make_reader

import armfleet
from armfleet.messages import ArmStatus, ControllerState, JointState, TFMessage, TransformStamped
from armfleet.recording import open_recording
from armfleet.recording.encode import (
    ControllerStateEncoder,
    encoder_for,
    rotation_to_quaternion,
)
from armfleet.recording.mcap_sink import McapSink
from armfleet.recording.replay_stream import ArmAppeared, ArmRemoved, replay_events
from armfleet.recording.schemas import TF_MESSAGE
from tests.conftest import RecordedRun

#: Status reports per second (world.STATUS_PERIOD_S = 0.1 s).
STATUS_RATE_HZ = 10.0
#: The broadcaster's and controller's shipped rate, one per 1 ms step.
CONTROL_RATE_HZ = 1000.0


def read_mcap(path: Path) -> tuple[Any, dict[str, list[tuple[int, bytes]]]]:
    """(summary, messages by topic) straight from the ``mcap`` library."""
    by_topic: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        for _, channel, message in reader.iter_messages(log_time_order=False):
            by_topic[channel.topic].append((message.log_time, message.data))
    return summary, by_topic


@pytest.fixture(scope="module")
def contents(recorded_run: RecordedRun) -> tuple[Any, dict[str, list[tuple[int, bytes]]]]:
    return read_mcap(recorded_run.path)


def rate_hz(times_ns: list[int]) -> float:
    return (len(times_ns) - 1) / ((times_ns[-1] - times_ns[0]) / 1e9)


# -- topics, counts, rates -------------------------------------------------------------------
def test_every_topic_is_recorded(recorded_run: RecordedRun, contents: Any) -> None:
    summary, _ = contents
    recorded = {channel.topic for channel in summary.channels.values()}
    world_topics = set(recorded_run.topics)
    assert world_topics <= recorded, world_topics - recorded
    assert recorded - world_topics == {
        "/bob/robot_description",
        "/toby/robot_description",
        "/bob/robot_meshes",
        "/toby/robot_meshes",
    }
    # The topics published only for listeners were published (and recorded).
    assert {"/tf", "/bob/position_controller/state"} <= world_topics


def test_message_counts_are_those_published(recorded_run: RecordedRun, contents: Any) -> None:
    summary, by_topic = contents
    published = Counter(topic for topic, _, _ in recorded_run.messages)
    # The latched /tf_static of both arms (published before the second listener) count too.
    published["/tf_static"] = 2
    counts = {
        channel.topic: summary.statistics.channel_message_counts.get(channel_id, 0)
        for channel_id, channel in summary.channels.items()
    }
    own = ("/robot_description", "/robot_meshes")  # the recorder's, not the bus's: one per arm
    assert {topic: n for topic, n in counts.items() if not topic.endswith(own)} == {
        topic: published.get(topic, 0) for topic in recorded_run.topics
    }
    assert all(n == 1 for topic, n in counts.items() if topic.endswith(own))
    assert all(len(by_topic[topic]) == n for topic, n in counts.items() if n)


def test_rates_match_the_controllers_and_the_world(contents: Any) -> None:
    _, by_topic = contents
    for arm in ("bob", "toby"):
        states = [t for t, _ in by_topic[f"/{arm}/joint_states"]]
        controller = [t for t, _ in by_topic[f"/{arm}/position_controller/state"]]
        status = [t for t, _ in by_topic[f"/{arm}/status"]]
        assert rate_hz(states) == pytest.approx(CONTROL_RATE_HZ, rel=1e-6)
        assert rate_hz(controller) == pytest.approx(CONTROL_RATE_HZ, rel=1e-6)
        assert rate_hz(status) == pytest.approx(STATUS_RATE_HZ, rel=1e-6)
        assert len(states) > 2000  # 2 s of motion and the bring-up
    # robot_state_publisher: one /tf message per joint state of each arm.
    tf = len(by_topic["/tf"])
    assert tf == len(by_topic["/bob/joint_states"]) + len(by_topic["/toby/joint_states"])
    assert len(by_topic["/bob/position_controller/commands"]) == 1
    assert len(by_topic["/bringup"]) == 8  # 4 stages x 2 arms
    assert "/collisions" not in by_topic  # no contact, yet the channel is there


def test_log_times_are_simulated_time_and_monotonic(
    recorded_run: RecordedRun, contents: Any
) -> None:
    _, by_topic = contents
    for topic, messages in by_topic.items():
        times = [t for t, _ in messages]
        assert times == sorted(times), topic
    # Log time = simulated time, equal to the stamp of the stamped messages.
    for log_time, data in by_topic["/bob/joint_states"][::97]:
        stamp = json.loads(data)["header"]["stamp"]
        assert stamp["sec"] * 1_000_000_000 + stamp["nanosec"] == log_time
        assert stamp["nsec"] == stamp["nanosec"]
    last = max(t for messages in by_topic.values() for t, _ in messages)
    assert last == max(t for _, t, _ in recorded_run.messages)


# -- schemas ---------------------------------------------------------------------------------
def test_schemas_are_valid_json_schemas_and_every_message_fits(contents: Any) -> None:
    summary, by_topic = contents
    validators: dict[str, Any] = {}
    for channel in summary.channels.values():
        schema_record = summary.schemas[channel.schema_id]
        assert schema_record.encoding == "jsonschema"
        assert channel.message_encoding == "json"
        schema = json.loads(schema_record.data)
        jsonschema.Draft202012Validator.check_schema(schema)
        assert "$ref" not in schema_record.data.decode()  # self-contained, as Foxglove wants
        validators[channel.topic] = jsonschema.Draft202012Validator(schema)
    checked = 0
    for topic, messages in by_topic.items():
        # Every message of a slow topic; a spread of the 1 kHz ones (they share templates).
        step = 1 if len(messages) < 100 else 53
        for _, data in messages[::step] + messages[-1:]:
            validators[topic].validate(json.loads(data))
            checked += 1
    assert checked > 250


def test_ros_schema_names(contents: Any) -> None:
    summary, _ = contents
    names = {
        channel.topic: summary.schemas[channel.schema_id].name
        for channel in summary.channels.values()
    }
    assert names["/tf"] == names["/tf_static"] == "tf2_msgs/msg/TFMessage"
    assert names["/bob/joint_states"] == "sensor_msgs/msg/JointState"
    assert names["/bob/position_controller/commands"] == "std_msgs/msg/Float64MultiArray"
    assert (
        names["/bob/position_controller/state"] == "control_msgs/msg/JointTrajectoryControllerState"
    )
    assert names["/bob/robot_description"] == "std_msgs/msg/String"
    assert names["/bob/status"] == "armfleet_msgs/msg/ArmStatus"


# -- what the messages hold ------------------------------------------------------------------
def test_joint_states_read_back_exactly(recorded_run: RecordedRun, contents: Any) -> None:
    _, by_topic = contents
    live = [m for topic, _, m in recorded_run.messages if topic == "/bob/joint_states"]
    recorded = [json.loads(data) for _, data in by_topic["/bob/joint_states"]]
    assert len(recorded) == len(live)
    for message, state in zip(recorded, live, strict=True):
        assert tuple(message["name"]) == state.name
        assert message["position"] == state.position.tolist()  # 17 digits: the same doubles
        assert message["velocity"] == state.velocity.tolist()
        assert message["effort"] == state.effort.tolist()


def test_tracking_error_is_reference_minus_feedback(contents: Any) -> None:
    _, by_topic = contents
    moving = 0
    for _, data in by_topic["/bob/position_controller/state"][::41]:
        message = json.loads(data)
        reference = np.array(message["reference"]["positions"])
        feedback = np.array(message["feedback"]["positions"])
        assert message["error"]["positions"] == pytest.approx(reference - feedback, abs=1e-15)
        moving += any(v != 0.0 for v in message["reference"]["velocities"])
    assert moving > 5


def matrix_of(transform: dict[str, Any]) -> np.ndarray:
    t, q = transform["translation"], transform["rotation"]
    x, y, z, w = q["x"], q["y"], q["z"], q["w"]
    matrix = np.eye(4)
    matrix[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    matrix[:3, 3] = t["x"], t["y"], t["z"]
    return matrix


def test_transforms_are_the_worlds(recorded_run: RecordedRun, contents: Any) -> None:
    _, by_topic = contents
    live = [m for topic, _, m in recorded_run.messages if topic == "/tf"]
    for index in (0, len(live) // 2, len(live) - 1):
        message = json.loads(by_topic["/tf"][index][1])
        assert len(message["transforms"]) == len(live[index].transforms)
        for recorded, transform in zip(message["transforms"], live[index].transforms, strict=True):
            assert recorded["header"]["frame_id"] == transform.frame_id
            assert recorded["child_frame_id"] == transform.child_frame_id
            assert matrix_of(recorded["transform"]) == pytest.approx(transform.matrix, abs=1e-12)


def test_static_transforms_place_each_base(contents: Any) -> None:
    _, by_topic = contents
    bases = {}
    for _, data in by_topic["/tf_static"]:
        for transform in json.loads(data)["transforms"]:
            if transform["header"]["frame_id"] == "world":
                bases[transform["child_frame_id"]] = matrix_of(transform["transform"])
    assert set(bases) == {"bob_base_link", "toby_base_link"}
    toby = armfleet.SpawnPose(1.0, 0.0, 0.0, 180.0).matrix()
    assert bases["toby_base_link"] == pytest.approx(toby, abs=1e-12)


def test_urdfs_spec_and_arms_are_in_the_file(recorded_run: RecordedRun) -> None:
    recording = open_recording(recorded_run.path)
    assert recording.complete
    assert recording.arm_names == ("bob", "toby")
    for name, (urdf, joints) in recorded_run.arms.items():
        arm = recording.arm(name)
        assert arm.urdf == urdf
        assert arm.joint_names == joints
        assert arm.model == "panda" and arm.removed_ns is None
    assert recording.arm("toby").pose == armfleet.SpawnPose(1.0, 0.0, 0.0, 180.0)
    assert recording.spec_text is not None
    assert "name: toby" in recording.spec_text and "yaw_deg: 180.0" in recording.spec_text
    assert recording.run["dt_s"] == "0.001" and recording.run["started_ns"] == "0"
    with recorded_run.path.open("rb") as stream:
        names = [a.name for a in make_reader(stream).iter_attachments()]
    assert sorted(names) == ["bob.urdf", "launch_spec.yaml", "toby.urdf"]


def test_robot_description_points_foxglove_at_the_meshes(contents: Any) -> None:
    _, by_topic = contents
    urdf = json.loads(by_topic["/bob/robot_description"][0][1])["data"]
    meshes = [part.split('"')[0] for part in urdf.split('filename="')[1:]]
    assert meshes and all(m.startswith("file:///") for m in meshes)
    assert all(Path(m.removeprefix("file://")).is_file() for m in meshes)


# -- arms that come and go -------------------------------------------------------------------
def test_arms_spawned_later_and_removed_are_recorded(tmp_path: Path) -> None:
    path = tmp_path / "later.mcap"
    with armfleet.World() as world:
        world.spawn("bob")
        with armfleet.record(world, path):
            world.run(0.1)
            world.spawn("carl", at=(1.0, 0.0))
            carl_time = world.time
            world.run(0.1)
            world.remove("bob")
            removed_time = world.time
            world.run(0.2)  # the next status report (10 Hz) shows bob gone
    recording = open_recording(path)
    bob, carl = recording.arm("bob"), recording.arm("carl")
    assert bob.spawned_ns == recording.start_ns == 0 or bob.spawned_ns < carl.spawned_ns
    assert bob.removed_ns is not None
    assert removed_time <= bob.removed_ns / 1e9 <= removed_time + 0.1 + 1e-9
    assert carl.removed_ns is None
    assert carl.spawned_ns / 1e9 <= carl_time
    statics = list(recording.messages(["/tf_static"]))
    assert len(statics) == 2  # bob's (latched) at the start, carl's when it came
    assert {t["child_frame_id"] for t in statics[1].data["transforms"]} >= {"carl_base_link"}
    events = [e for e in replay_events(recording) if isinstance(e, ArmAppeared | ArmRemoved)]
    names = [e.arm.name if isinstance(e, ArmAppeared) else e.name for e in events]
    assert list(zip([type(e).__name__ for e in events], names, strict=True)) == [
        ("ArmAppeared", "bob"),
        ("ArmAppeared", "carl"),
        ("ArmRemoved", "bob"),
    ]


def test_named_topics_are_recorded_without_turning_on_the_others(tmp_path: Path) -> None:
    """With topic names (no patterns), /tf is not computed for the recorder."""
    path = tmp_path / "named.mcap"
    with armfleet.World() as world:
        bob = world.spawn("bob")
        with armfleet.record(world, path, topics=["/bob/joint_states", "/tf_static"]):
            assert not world.bus.has_subscribers("/tf")
            bob.move_to(bob.positions + 0.1)
            world.run(0.1)
    recording = open_recording(path)
    assert {t for t, info in recording.topics.items() if info.message_count} == {
        "/bob/joint_states",
        "/tf_static",
    }
    assert recording.topics["/bob/joint_states"].message_count == 100


# -- robustness ------------------------------------------------------------------------------
def test_a_killed_writer_leaves_a_readable_file(tmp_path: Path) -> None:
    """Without stop(), the file has no summary; everything up to the last chunk reads back."""
    path = tmp_path / "killed.mcap"
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child dies without cleaning up
        try:
            world = armfleet.World()
            bob = world.spawn("bob")
            armfleet.record(world, path)
            bob.move_to(bob.positions + 0.2)
            world.run(1.0)
        finally:
            os.kill(os.getpid(), signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
    recording = open_recording(path)
    assert not recording.complete
    assert recording.arm_names == ("bob",)  # metadata and URDFs are written at once
    states = list(recording.messages(["/bob/joint_states"]))
    assert len(states) > 100
    times = [m.log_time_ns for m in states]
    assert times == sorted(times)
    assert recording.topics["/bob/joint_states"].message_count == len(states)


def test_an_interrupt_while_writing_waits_for_the_write() -> None:
    """In a process of its own, whose main thread is the test's (a pytest-xdist worker may
    run tests elsewhere, and Python's signal handlers run in the main thread only)."""
    code = (
        "import signal\n"
        # As in a terminal, whatever this test's own parent ignores (a job started with &).
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "from armfleet.recording.interrupts import deferred_interrupts\n"
        "order = []\n"
        "try:\n"
        "    with deferred_interrupts():\n"
        "        signal.raise_signal(signal.SIGINT)\n"
        "        order.append('write finished')\n"
        "except KeyboardInterrupt:\n"
        "    order.append('interrupted')\n"
        "print(order, signal.getsignal(signal.SIGINT) is signal.default_int_handler)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    assert result.stdout.strip() == "['write finished', 'interrupted'] True", result.stderr


def test_a_sink_closes_once_and_refuses_writes_after(tmp_path: Path) -> None:
    sink = McapSink(tmp_path / "x.mcap", "test")
    channel = sink.add_channel("/tf", TF_MESSAGE, {})
    sink.write(channel, 1, b'{"transforms":[]}')
    sink.close()
    sink.close()
    sink.write(channel, 2, b'{"transforms":[]}')  # ignored
    assert sink.message_count == 1
    with pytest.raises(armfleet.RecordingError, match="closed"):
        sink.add_channel("/x", TF_MESSAGE, {})


# -- encoding --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "axis", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -1, 0), (0, 1, -1), (1, 2, 3)]
)
@pytest.mark.parametrize("angle", [0.0, 0.3, math.pi / 2, math.pi - 1e-9, math.pi])
def test_quaternions_are_exact_also_at_half_turns(axis: tuple[float, ...], angle: float) -> None:
    u = np.array(axis, dtype=float) / np.linalg.norm(axis)
    expected = (*(u * math.sin(angle / 2)), math.cos(angle / 2))
    k = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    matrix = np.eye(4)
    matrix[:3, :3] = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
    q = np.array(rotation_to_quaternion(matrix.ravel().tolist()))
    sign = 1.0 if np.dot(q, expected) >= 0 else -1.0  # q and -q are one rotation
    assert sign * q == pytest.approx(expected, abs=1e-8)


def test_non_finite_numbers_are_not_written() -> None:
    """JSON has no NaN: an array holding one is written empty ("not available" in ROS),
    a transform holding one is left out (see tests/test_recording_schemas.py)."""
    state = JointState(
        1.5, ("a", "b"), np.array([0.1, np.nan]), np.array([0.0, 0.0]), np.array([np.inf, 1.0])
    )
    message = json.loads(encoder_for(JointState)(state))
    assert message["position"] == [] and message["effort"] == []
    assert message["velocity"] == [0.0, 0.0]
    assert message["header"]["stamp"] == {"sec": 1, "nanosec": 500_000_000, "nsec": 500_000_000}
    good = TransformStamped(0.0, "a", "c", np.eye(4))
    broken = TFMessage((TransformStamped(0.0, "a", "b", np.full((4, 4), np.nan)), good))
    transforms = json.loads(encoder_for(TFMessage)(broken))["transforms"]
    assert [t["child_frame_id"] for t in transforms] == ["c"]


def test_fast_and_plain_encodings_agree() -> None:
    """The 1 kHz templates write what the generic path would (numbers compared as floats)."""
    rng = np.random.default_rng(0)
    ref_q, ref_v, ref_a, q, v = (rng.normal(size=2) for _ in range(5))
    state = ControllerState(0.123, ("j1", "j2"), ref_q, ref_v, ref_a, q, v, True)
    fast = json.loads(encoder_for(ControllerState)(state))
    assert fast["reference"]["accelerations"] == state.reference_acceleration.tolist()
    assert fast["feedback"]["velocities"] == state.velocity.tolist()
    assert fast["joint_names"] == ["j1", "j2"]
    assert fast["desired"] == fast["reference"] and fast["actual"] == fast["feedback"]
    assert fast == json.loads(ControllerStateEncoder()._slow(state))
    status = ArmStatus(0.25, "bob", armfleet.messages.ArmMode.MOVING, "", (0, 3))
    assert json.loads(encoder_for(ArmStatus)(status)) == {
        "header": {
            "stamp": {"sec": 0, "nanosec": 250_000_000, "nsec": 250_000_000},
            "frame_id": "",
        },
        "arm": "bob",
        "mode": "moving",
        "reason": "",
        "saturation_steps": [0, 3],
    }


# -- bad input -------------------------------------------------------------------------------
def test_bad_recorder_input(tmp_path: Path) -> None:
    with armfleet.World() as world:
        with pytest.raises(armfleet.RecordingError, match=r"ending in \.mcap"):
            armfleet.Recorder(world, tmp_path / "run.bag")
        with pytest.raises(armfleet.RecordingError, match="cannot write the recording"):
            armfleet.record(world, tmp_path / "missing" / "run.mcap")
        recorder = armfleet.record(world, tmp_path / "run.mcap")
        with pytest.raises(armfleet.RecordingError, match="already started"):
            recorder.start()
        recorder.stop()
    with pytest.raises(armfleet.ArmfleetError, match="closed"):
        armfleet.record(world, tmp_path / "late.mcap")


def test_bad_files_to_read(tmp_path: Path) -> None:
    with pytest.raises(armfleet.RecordingError, match="does not exist"):
        open_recording(tmp_path / "nope.mcap")
    (tmp_path / "text.mcap").write_text("not an mcap")
    with pytest.raises(armfleet.RecordingError, match="not an MCAP recording"):
        open_recording(tmp_path / "text.mcap")
    (tmp_path / "empty.mcap").write_bytes(b"")
    with pytest.raises(armfleet.RecordingError, match="empty"):
        open_recording(tmp_path / "empty.mcap")
    with pytest.raises(armfleet.RecordingError, match="is a folder, not a regular file"):
        open_recording(tmp_path)


def test_the_recorded_spec_launches_the_same_arms(
    recorded_run: RecordedRun, tmp_path: Path
) -> None:
    text = open_recording(recorded_run.path).spec_text
    assert text is not None
    (tmp_path / "again.yaml").write_text(text)
    again = armfleet.load_spec(tmp_path / "again.yaml")
    assert again.arms == recorded_run.spec.arms
    assert again.world == recorded_run.spec.world


def test_world_record_is_the_same_recorder(tmp_path: Path) -> None:
    path = tmp_path / "world.mcap"
    with armfleet.World() as world:
        bob = world.spawn("bob")
        with world.record(path):
            bob.move_to(bob.positions + 0.1)
            world.run(0.2)
    recording = armfleet.open_recording(path)
    assert recording.arm_names == ("bob",)
    assert 0.19 <= recording.duration_s <= 0.21
    counts = {m.topic for m in recording.messages(["/bob/joint_states"])}
    assert counts == {"/bob/joint_states"}
