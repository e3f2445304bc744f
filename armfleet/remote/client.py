"""``armfleet.connect()``: command and watch a running world from another process."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from armfleet.checks import number_ranges
from armfleet.checks.model_reference import is_model_file
from armfleet.checks.network_address import normalize_address
from armfleet.description.model_options import options_from_keywords
from armfleet.errors import ArmfleetError
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.messages import FloatArray, JointCommand, Positions
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M
from armfleet.remote import runtime_file
from armfleet.remote.remote_arm import RemoteArm
from armfleet.remote.remote_subscription import RemoteSubscription
from armfleet.remote.request_channel import RequestChannel
from armfleet.remote.stream_receiver import StreamReceiver
from armfleet.remote.world_info import ObjectInfo, TopicInfo, WorldInfo
from armfleet.services.errors import NoWorldFound, RequestTimeout
from armfleet.services.planning_options import planning_request
from armfleet.services.protocol import (
    DEFAULT_QUEUE_SIZE,
    HARD_FRAME_LIMIT_BYTES,
    PROTOCOL_VERSION,
    armfleet_version,
)

#: Wait for most requests [s].
DEFAULT_TIMEOUT_S = 5.0
#: Wait for a spawn: it queues behind other bring-ups [s].
SPAWN_TIMEOUT_S = 120.0
#: Wall time a ``step`` request may take per step, on top of the timeout [s]: a world of
#: 16 Pandas steps in 2.2 ms on a loaded 2-core machine; other clients' requests run
#: between the slices of a long step (:mod:`armfleet.remote.sliced_steps`).
STEP_ALLOWANCE_S = 0.01


class Client:
    """A connection to a running world, shaped like the in-process API.

    Use :func:`connect` to make one. Calls are safe from several threads (they
    take turns); subscription callbacks run in the client's stream thread.

    Args:
        address: ``tcp://HOST:PORT`` of the world.
        timeout: default wait for a reply [s].
    """

    def __init__(self, address: str, timeout: float = DEFAULT_TIMEOUT_S) -> None:
        self.address = address
        self.timeout = timeout
        self._context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        self._context.setsockopt(zmq.MAXMSGSIZE, HARD_FRAME_LIMIT_BYTES)
        self._channel = RequestChannel(self._context, address)
        self._stream: StreamReceiver | None = None
        #: The key naming the request connection (from ``hello``): our streams attach with it.
        self._connection: str | None = None
        self._closed = False

    def call(
        self,
        op: str,
        args: dict[str, Any] | None = None,
        timeout: float | None = None,
        *,
        work_s: float = 0.0,
    ) -> Any:
        """Send request ``op`` with ``args`` and return the world's result (low level).

        Args:
            timeout: wait for the world to take the request up and answer [s]
                (:attr:`timeout` if None).
            work_s: how long the work may take in the world once started [s] (a plan's
                budget), waited for on top of ``timeout``.
        """
        wait = self.timeout if timeout is None else timeout
        return self._channel.call(op, args, wait, work_s)

    def hello(self, timeout: float | None = None) -> dict[str, Any]:
        """Check that the world answers and speaks this client's protocol."""
        args = {"protocol": PROTOCOL_VERSION, "client": armfleet_version()}
        result: dict[str, Any] = self.call("hello", args, timeout)
        connection = result.get("connection")
        self._connection = connection if isinstance(connection, str) else None
        return result

    # -- the world --------------------------------------------------------------------
    def info(self) -> WorldInfo:
        """Simulated time, step, real-time factor, paused or not, arms."""
        return WorldInfo.from_wire(self.call("info"))

    def pause(self) -> float:
        """Stop stepping at the next step boundary (requests are still served);
        return the simulated time it stopped at [s]."""
        return float(self.call("pause")["time_s"])

    def resume(self) -> float:
        return float(self.call("resume")["time_s"])

    def step(self, count: int = 1) -> float:
        """Advance a paused world ``count`` steps; return its simulated time [s].

        Raises:
            InvalidNumber: ``count`` is not an integer in 1..100000 (nothing is sent).
        """
        number_ranges.STEP_COUNT.check(count, "step count")
        work_s = STEP_ALLOWANCE_S * count
        return float(self.call("step", {"count": count}, work_s=work_s)["time_s"])

    # -- arms -------------------------------------------------------------------------
    @property
    def arms(self) -> dict[str, RemoteArm]:
        """Arms by name, in bring-up order."""
        return {d["name"]: RemoteArm(self, d) for d in self.call("arms")}

    def arm(self, name: str) -> RemoteArm:
        """The arm ``name``; raises if the world has none such."""
        return RemoteArm(self, self.call("arm", {"name": name}))

    def spawn(
        self,
        name: str,
        model: str = "panda",
        at: Sequence[float] | SpawnPose | str = (0.0, 0.0),
        *,
        initial_positions: Positions | None = None,
        parameters: Mapping[str, Mapping[str, float]] | None = None,
        xacro_args: Mapping[str, str] | None = None,
        tool_link: str | None = None,
        gripper_joints: Sequence[str] | None = None,
        home: Positions | None = None,
        end_effector: Mapping[str, Any] | str | None = None,
        timeout: float = SPAWN_TIMEOUT_S,
    ) -> RemoteArm:
        """Bring an arm up in the world (after any bring-up already queued) and return it.

        Args:
            name: arm name (``^[a-z][a-z0-9_]*$``), unique in the world.
            model: one of the world's models (``armfleet models``), or a model file: the
                world's process reads it, so a relative path is made absolute here and
                must name a file that process can read.
            at: ``(x, y[, z[, yaw_deg]])`` [m, deg], a :class:`SpawnPose`, or ``"X,Y"``.
            initial_positions: arm joint positions at spawn [rad]; the model's home if None.
            parameters: per-controller parameter overrides for this arm.
            xacro_args: arguments of a xacro model file.
            tool_link, gripper_joints, home, end_effector: what the model file does not
                say, as :meth:`armfleet.World.spawn` takes them; the end effector's file
                is read by the world's process too (made absolute here).
            timeout: wait for the arm to be ready [s].

        Raises:
            ModelSettingError: a bad setting (checked here, before anything is sent).
        """
        if isinstance(model, str) and is_model_file(model) and not model.startswith("package:"):
            model = str(Path(model).expanduser().absolute())
        options = options_from_keywords(
            "spawn",
            xacro_args=xacro_args,
            tool_link=tool_link,
            gripper_joints=gripper_joints,
            home=home,
            end_effector=end_effector,
        )
        args: dict[str, Any] = {"name": name, "model": model, "at": _pose(at)}
        args.update(options.to_mapping())
        if initial_positions is not None:
            args["initial_positions"] = [float(v) for v in initial_positions]
        if parameters:
            args["parameters"] = {c: dict(values) for c, values in parameters.items()}
        return RemoteArm(self, self.call("spawn", args, timeout))

    def remove(self, name: str) -> None:
        """Take the arm ``name`` out of the world."""
        self.call("remove", {"name": name})

    def move_together(
        self,
        targets: Mapping[str, Positions],
        *,
        avoid_collisions: bool = False,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> float:
        """Start several arms on the same step so that they finish at the same instant,
        as :meth:`armfleet.World.move_together`.

        Args:
            targets: per arm name, joint positions (one per ``arm.joint_names``) [rad or m].
            avoid_collisions: plan the arms jointly around each other and everything
                else, instead of each in a straight line; they must be at rest.
            clearance_m: margin the plan keeps from other bodies [m], in [0.001, 0.5].
            timeout_s: the plan's time budget [s], in [0.001, 60] (1 s by default);
                this call waits that long on top of the client's timeout.
            budget: instead of ``timeout_s``, planner iterations (an integer in
                1..1000000): the same request gives the same path under any load.

        Returns:
            The common duration [s].

        Raises:
            RemoteError: an unknown arm or any bad target; then no arm moves.
            RemotePlanningFailed: with ``avoid_collisions``, no plan (a
                :class:`~armfleet.planning.PlanningFailed`, with its ``reason``); no arm
                moves.
            InvalidFlag, InvalidNumber: ``avoid_collisions``, ``clearance_m``,
                ``timeout_s`` or ``budget`` is invalid (nothing is sent).
        """
        planning, work_s = planning_request(avoid_collisions, clearance_m, timeout_s, budget)
        wire = {name: _floats(values) for name, values in targets.items()}
        args = {"targets": wire, **planning}
        return float(self.call("move_together", args, work_s=work_s)["duration_s"])

    # -- objects ----------------------------------------------------------------------
    @property
    def objects(self) -> dict[str, ObjectInfo]:
        """Scene objects by name, in the order they were added, where they are now."""
        return {d["name"]: ObjectInfo.from_wire(d) for d in self.call("objects")}

    def add_object(
        self,
        name: str,
        shape: str,
        *,
        size: float | Sequence[float],
        mass: float | None = None,
        friction: float | None = None,
        color: Sequence[float] | None = None,
        at: Sequence[float] = (0.0, 0.0, 0.0),
        rpy_deg: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> ObjectInfo:
        """Add a box, cylinder or sphere, as :meth:`armfleet.World.add_object` does (a
        mesh names a file on the world's machine: add it there).

        Args:
            size: box (x, y, z) full extents; cylinder (radius, length); sphere radius [m].
            mass: [kg] (the world's default if None); 0 makes it static, like a table.
            at: (x, y, z) of its frame [m]; rpy_deg: roll, pitch, yaw [deg].
        """
        args: dict[str, Any] = {
            "name": name,
            "shape": shape,
            "size": size if isinstance(size, int | float) else _floats(size),
            "at": _floats(at),
            "rpy_deg": _floats(rpy_deg),
        }
        optional = {"mass": mass, "friction": friction}
        args |= {key: value for key, value in optional.items() if value is not None}
        if color is not None:
            args["color"] = _floats(color)
        return ObjectInfo.from_wire(self.call("add_object", args))

    def remove_object(self, name: str) -> None:
        """Take the object ``name`` out of the world."""
        self.call("remove_object", {"name": name})

    # -- frames -----------------------------------------------------------------------
    def lookup(self, target_frame: str, source_frame: str) -> FloatArray:
        """4x4 pose of ``source_frame`` in ``target_frame`` now, as ``world.tf.lookup``
        (frames: ``world``, the arms' prefixed links, the objects)."""
        result = self.call("lookup", {"target": target_frame, "source": source_frame})
        return np.reshape(np.asarray(result["matrix"], dtype=float), (4, 4))

    # -- topics -----------------------------------------------------------------------
    def topics(self) -> dict[str, TopicInfo]:
        """The world's topics by name."""
        return {
            t["topic"]: TopicInfo(t["topic"], t["type"], bool(t["command"]))
            for t in self.call("topics")
        }

    def subscribe(
        self,
        topic: str,
        callback: Callable[[Any], None],
        rate_hz: float | None = None,
        *,
        queue_size: int = DEFAULT_QUEUE_SIZE,
    ) -> RemoteSubscription:
        """Call ``callback(message)`` for messages on ``topic`` (a message class of
        :mod:`armfleet.messages`, as in the world), in the client's stream thread.

        Args:
            rate_hz: at most this many messages per second of wall time; all if None.
            queue_size: messages kept for a slow callback; the oldest are dropped
                beyond (see :attr:`RemoteSubscription.dropped`).
        """
        stream = self._open_stream()
        local = stream.add(topic, callback, queue_size)
        args: dict[str, Any] = {
            "topic": topic,
            "stream": stream.token,
            "sub": local.key,
            "queue_size": queue_size,
        }
        if rate_hz is not None:
            args["rate_hz"] = rate_hz
        try:
            result = self.call("subscribe", args)
        except BaseException:
            stream.remove(local.key)
            raise
        return RemoteSubscription(local, str(result["type"]), self._unsubscribe)

    def publish(self, topic: str, message: JointCommand | Positions) -> None:
        """Publish on a command topic (``/<arm>/position_controller/commands``); checked
        by the world like :meth:`RemoteArm.move_to`."""
        positions = message.positions if isinstance(message, JointCommand) else message
        self.call("publish", {"topic": topic, "message": {"positions": _floats(positions)}})

    def _open_stream(self) -> StreamReceiver:
        if self._closed:
            raise ArmfleetError("this client is closed")
        if self._stream is None or not self._stream.alive:
            if self._connection is None:
                self.hello()  # the key that makes the stream ours
            self._stream = StreamReceiver(
                self._context, self.address, self.timeout, self._connection
            )
        return self._stream

    def _unsubscribe(self, key: int) -> None:
        stream = self._stream
        if stream is None:
            return
        stream.remove(key)
        with contextlib.suppress(ArmfleetError):  # the world may be gone already
            self.call("unsubscribe", {"stream": stream.token, "sub": key})

    # -- lifetime ---------------------------------------------------------------------
    def close(self) -> None:
        """Cancel the subscriptions and close the connection (idempotent)."""
        if self._closed:
            return
        self._closed = True
        stream_stopped = True
        if self._stream is not None:
            self._stream.close()
            stream_stopped = not self._stream.alive
        self._channel.close()
        if stream_stopped:
            self._context.term()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Client({self.address!r})"


def find_world(address: str | None = None) -> tuple[str, str]:
    """The address to use and where it came from (for messages).

    Raises:
        NoWorldFound: no address given and no live world in the runtime file.
    """
    if address is not None:
        return normalize_address(address), "given"
    path = runtime_file.runtime_path()
    entry = runtime_file.read_entry(path)
    start = "start one with 'armfleet spawn bob --at 0,0', or give its address (--connect ADDR)"
    if entry is None:
        raise NoWorldFound(f"no running world found (no {path}); {start}")
    if not entry.alive:
        raise NoWorldFound(
            f"no running world found ({path} names process {entry.pid}, which has ended); {start}"
        )
    return entry.address, f"named by {path}, process {entry.pid}"


def connect(address: str | None = None, *, timeout: float = DEFAULT_TIMEOUT_S) -> Client:
    """Connect to a running world.

    Args:
        address: ``tcp://HOST:PORT`` (or ``HOST:PORT``, ``PORT``); by default the
            world named in the per-user runtime file (``armfleet spawn`` writes it).
        timeout: default wait for replies, and for the world to answer now [s].

    Raises:
        NoWorldFound: no world runs, or none answers at ``address``.
        InvalidNumber: ``timeout`` is not in [0.001, 600] s.
    """
    number_ranges.REQUEST_TIMEOUT_S.check(timeout, "timeout")
    resolved, source = find_world(address)
    client = Client(resolved, timeout)
    try:
        client.hello()
    except RequestTimeout:
        client.close()
        raise NoWorldFound(
            f"no answer from a world at {resolved} ({source}) within {timeout:g} s"
        ) from None
    except BaseException:
        client.close()
        raise
    return client


def _pose(at: Sequence[float] | SpawnPose | str) -> Any:
    if isinstance(at, str):
        at = SpawnPose.parse(at)
    if isinstance(at, SpawnPose):
        return {
            "x": at.x,
            "y": at.y,
            "z": at.z,
            "yaw_deg": at.yaw_deg,
            "roll_deg": at.roll_deg,
            "pitch_deg": at.pitch_deg,
        }
    return _floats(at)


def _floats(values: Any) -> list[Any]:
    """Numbers as floats; anything else as given, for the world to name the problem."""
    return [
        float(v) if isinstance(v, int | float) and not isinstance(v, bool) else v for v in values
    ]
