"""The wire format: every bus message survives the trip as plain msgpack, nothing else does."""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest

from armfleet import messages
from armfleet.checks.network_address import AddressError, is_loopback, normalize_address
from armfleet.messages import (
    ArmMode,
    ArmStatus,
    BringupEvent,
    BringupStage,
    CollisionReport,
    Contact,
    ControllerState,
    GripperCommand,
    GripperMode,
    GripperState,
    JointCommand,
    JointState,
    PlannedMotion,
    TFMessage,
    TransformStamped,
)
from armfleet.services.codec import (
    decode_message,
    message_types,
    pack,
    to_wire,
    unpack,
    unpack_request,
)
from armfleet.services.errors import ProtocolError
from armfleet.services.protocol import MAX_REQUEST_BYTES
from armfleet.services.run_state import RunState
from armfleet.services.subscription_queue import SubscriptionQueue

NAMES = ("bob_panda_joint1", "bob_panda_joint2")
STATE = JointState(1.5, NAMES, np.array([0.1, -0.2]), np.array([0.0, 1.0]), np.array([2.0, -3.0]))
TRANSFORM = TransformStamped(0.25, "world", "bob_base_link", np.eye(4))
SAMPLES = [
    STATE,
    JointCommand((0.1, 0.2, -0.3)),
    ControllerState(
        2.0, NAMES, np.zeros(2), np.ones(2), np.full(2, -1.0), np.zeros(2), np.ones(2), True
    ),
    TFMessage((TRANSFORM, TRANSFORM)),
    BringupEvent("bob", BringupStage.READY, 0.021, 0.03),
    CollisionReport(
        3.0,
        (Contact("bob", "bob_panda_link7", "toby", "", (1.0, 2.0, 3.0), (0.0, 0.0, 1.0), 0.001),),
    ),
    ArmStatus(4.0, "bob", ArmMode.PROTECTIVE_STOP, "touched toby", (0, 3)),
    GripperCommand(0.04, False, 20.0),
    GripperState(5.0, 0.0395, 0.04, 12.5, GripperMode.SQUEEZING, True),
    PlannedMotion(
        2.5,
        ("bob_panda_joint1", "bob_panda_joint2"),
        (0.0, 0.8, 1.9),
        np.array([[0.0, 0.1], [0.5, -0.2], [1.0, 0.3]]),
        np.array([[0.3, 0.0, 0.5], [0.35, 0.1, 0.45], [0.4, 0.2, 0.4]]),
    ),
]


def plain(value: object) -> bool:
    """Only msgpack's own types: no numpy, no enums, no dataclasses."""
    if isinstance(value, dict):
        return all(isinstance(k, str) and plain(v) for k, v in value.items())
    if isinstance(value, list):
        return all(plain(v) for v in value)
    return value is None or type(value) in (bool, int, float, str)


def same(a: object, b: object) -> bool:
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(
            same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a)
        )
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and b.dtype == np.float64 and np.array_equal(a, b)
    if isinstance(a, tuple):
        return isinstance(b, tuple) and len(a) == len(b) and all(map(same, a, b))
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("message", SAMPLES, ids=lambda m: type(m).__name__)
def test_every_message_round_trips_through_plain_msgpack(message: object) -> None:
    wire = to_wire(message)
    assert plain(wire)
    back = decode_message(type(message).__name__, unpack(pack(wire)))
    assert same(message, back)


def test_every_message_type_of_the_bus_is_known_and_covered() -> None:
    defined = {
        name
        for name, value in vars(messages).items()
        if isinstance(value, type) and dataclasses.is_dataclass(value)
    }
    assert set(message_types()) == defined
    assert set().union(*map(kinds, SAMPLES)) == defined  # a new message needs a sample here


def kinds(value: object) -> set[str]:
    """Names of the dataclasses in ``value``, nested ones included."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        inner = [kinds(getattr(value, f.name)) for f in dataclasses.fields(value)]
        return {type(value).__name__}.union(*inner)
    if isinstance(value, tuple):
        return set().union(*map(kinds, value))
    return set()


def test_arrays_go_out_as_lists_of_floats() -> None:
    assert to_wire(np.array([1, 2], dtype=np.int64)) == [1.0, 2.0]
    assert to_wire(TRANSFORM)["matrix"][0] == [1.0, 0.0, 0.0, 0.0]
    assert to_wire(np.float32(0.5)) == 0.5


def test_a_malformed_message_from_the_world_is_a_protocol_error() -> None:
    with pytest.raises(ProtocolError, match="malformed JointState"):
        decode_message("JointState", {"stamp": 1.0, "name": []})
    with pytest.raises(ProtocolError, match="malformed JointState"):
        decode_message("JointState", to_wire(STATE) | {"stamp": "soon"})
    # A type this client does not know (a newer world) stays a plain map.
    assert decode_message("NewThing", {"a": 1}) == {"a": 1}


@pytest.mark.parametrize(
    "data",
    [b"", b"\xc1", pack({"a": 1}) + b"\x00", b"\x81\x01\x02", b"\xa2\xff\xfe"],
    ids=["empty", "reserved byte", "extra data", "integer map key", "invalid utf-8"],
)
def test_unreadable_frames_are_protocol_errors(data: bytes) -> None:
    with pytest.raises(ProtocolError, match="not a valid msgpack message"):
        unpack(data)


def test_requests_past_the_limit_are_refused_before_decoding() -> None:
    with pytest.raises(ProtocolError, match=f"limit of {MAX_REQUEST_BYTES} bytes"):
        unpack_request(b"\x00" * (MAX_REQUEST_BYTES + 1))
    assert unpack_request(pack({"op": "info"})) == {"op": "info"}


def test_the_subscription_queue_drops_the_oldest_and_counts() -> None:
    pushes: list[int] = []
    queue = SubscriptionQueue(3, on_push=lambda: pushes.append(1))
    for value in range(5):
        queue.push(value)
    assert (queue.dropped, queue.accepted, len(pushes)) == (2, 5, 5)
    assert [queue.pop(), queue.pop(), queue.pop(), queue.pop()] == [2, 3, 4, None]
    queue.close()
    queue.push(9)
    assert queue.pop() is None and queue.accepted == 5


def test_the_subscription_queue_limits_the_rate_in_wall_time() -> None:
    queue = SubscriptionQueue(1000, rate_hz=20.0)
    started = time.monotonic()
    while time.monotonic() - started < 0.5:
        queue.push(0)
        time.sleep(0.001)
    # 20 Hz for 0.5 s: about 10 messages (the first at once), never a burst.
    assert 8 <= queue.accepted <= 12


def test_run_state_reports_the_realtime_factor_and_zero_when_paused() -> None:
    state = RunState()
    assert state.realtime_factor is None
    state.note_progress(0.0, 100.0)
    state.note_progress(1.0, 100.5)
    assert state.realtime_factor == pytest.approx(2.0)
    state.pause()
    assert state.realtime_factor == 0.0
    state.resume()
    assert state.realtime_factor is None  # the pause is not counted as slowness


@pytest.mark.parametrize(
    ("given", "address"),
    [
        ("tcp://127.0.0.1:5555", "tcp://127.0.0.1:5555"),
        ("localhost:5555", "tcp://localhost:5555"),
        ("5555", "tcp://127.0.0.1:5555"),
        ("tcp://[::1]:5555", "tcp://[::1]:5555"),
    ],
)
def test_addresses_a_user_may_type(given: str, address: str) -> None:
    assert normalize_address(given) == address


@pytest.mark.parametrize(
    "given", ["", "tcp://", "udp://1.2.3.4:5", "host", "h:0", "h:70000", "*:5"]
)
def test_malformed_addresses_are_refused(given: str) -> None:
    with pytest.raises(AddressError):
        normalize_address(given)


def test_loopback_hosts() -> None:
    assert is_loopback("127.0.0.1") and is_loopback("127.0.0.2") and is_loopback("::1")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.0.2.2")
