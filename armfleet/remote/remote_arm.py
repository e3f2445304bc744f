"""A client's handle on one arm of a running world, shaped like :class:`armfleet.Arm`."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from armfleet.checks import number_ranges
from armfleet.checks.flags import flag
from armfleet.checks.real_numbers import all_real
from armfleet.errors import ArmfleetError, NoGripper
from armfleet.frames.spawn_pose import SpawnPose
from armfleet.messages import ArmMode, FloatArray, JointState, Positions
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M
from armfleet.remote.remote_gripper import RemoteGripper
from armfleet.remote.service_caller import ServiceCaller
from armfleet.services.codec import decode_message
from armfleet.services.planning_options import planning_request

#: Default wait for a motion to finish [s of wall time].
WAIT_TIMEOUT_S = 30.0
#: Extra wait for the world's answer to a wait [s].
WAIT_REPLY_MARGIN_S = 2.0


class RemoteArm:
    """One arm of the world a :class:`Client` is connected to.

    Its name, model, pose, joint names and limits are read once; every other
    property asks the world.
    """

    def __init__(self, client: ServiceCaller, description: dict[str, Any]) -> None:
        self._client = client
        self._name = str(description["name"])
        self._model = str(description["model"])
        self._pose = SpawnPose(**description["pose"])
        self._joint_names = tuple(description["joint_names"])
        self._lower = np.asarray(description["lower"], dtype=float)
        self._upper = np.asarray(description["upper"], dtype=float)
        gripper = description.get("gripper")
        self._gripper = None if gripper is None else RemoteGripper(client, self._name, gripper)

    @property
    def name(self) -> str:
        return self._name

    @property
    def namespace(self) -> str:
        return f"/{self._name}"

    @property
    def model(self) -> str:
        return self._model

    @property
    def pose(self) -> SpawnPose:
        """Spawn pose of ``<name>_base_link`` in the world."""
        return self._pose

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Prefixed names of the joints :meth:`move_to` controls, base to tool."""
        return self._joint_names

    @property
    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        """(lower, upper) position limits of :attr:`joint_names` [rad or m]."""
        return self._lower.copy(), self._upper.copy()

    @property
    def gripper(self) -> RemoteGripper:
        """The fingers: ``open()``, ``close(force)``, ``move_to(width)``, ``wait()``, ``width``.

        Raises:
            NoGripper: the model has no fingers.
        """
        if self._gripper is None:
            raise NoGripper(self._name, self._model)
        return self._gripper

    @property
    def has_gripper(self) -> bool:
        return self._gripper is not None

    @property
    def joint_state(self) -> JointState:
        """The latest message of ``/<name>/joint_states`` (every movable joint)."""
        state: JointState = decode_message(
            "JointState", self._client.call("joint_state", {"name": self._name})
        )
        return state

    @property
    def positions(self) -> FloatArray:
        """Current positions of :attr:`joint_names` [rad or m]."""
        return np.asarray(self._describe()["positions"], dtype=float)

    @property
    def mode(self) -> ArmMode:
        """Holding, moving, protective stop or error."""
        return ArmMode(self._describe()["mode"])

    @property
    def is_moving(self) -> bool:
        return self.mode is ArmMode.MOVING

    def move_to(
        self,
        positions: Positions,
        *,
        avoid_collisions: bool = False,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> float:
        """Send target ``positions`` (one per :attr:`joint_names`); returns once the world
        has accepted them, at a step boundary, the planned duration of the motion [s].

        Args:
            avoid_collisions: go around everything in the world instead of in a
                straight line (the arm must be at rest), as :meth:`armfleet.Arm.move_to`.
            clearance_m: margin the plan keeps from other bodies [m], in [0.001, 0.5].
            timeout_s: the plan's time budget [s], in [0.001, 60] (1 s by default);
                this call waits that long on top of the client's timeout.
            budget: instead of ``timeout_s``, planner iterations (an integer in
                1..1000000): the same request gives the same path under any load.

        Raises:
            RemoteError: the world refused them (wrong length, not finite, outside the
                limits, protective stop...); the current motion goes on.
            RemotePlanningFailed: with ``avoid_collisions``, no plan (a
                :class:`~armfleet.planning.PlanningFailed`, with its ``reason``); nothing
                moved.
            InvalidFlag, InvalidNumber: a planning option is invalid (nothing is sent).
        """
        planning, work_s = planning_request(avoid_collisions, clearance_m, timeout_s, budget)
        args = {"name": self._name, "positions": self._vector(positions), **planning}
        return float(self._client.call("move", args, work_s=work_s)["duration_s"])

    def move_to_pose(
        self,
        pose: Any,
        frame: str = "world",
        *,
        link: str = "tool0",
        linear: bool = False,
        avoid_collisions: bool = False,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        timeout_s: float | None = None,
        budget: int | None = None,
    ) -> float:
        """Move ``link`` to ``pose`` in ``frame``; returns, once the world has accepted the
        goal, the planned duration [s].

        Args:
            pose: a 4x4 homogeneous matrix, or ``(x, y, z)`` [m] to keep the link's
                current orientation (as seen from ``frame``).
            frame: a frame of the world's TF tree (``world``, ``toby_tool0``, an object).
            link: the arm's link to place, unprefixed or prefixed.
            linear: follow a straight line from where the link is (from rest).
            avoid_collisions, clearance_m, timeout_s, budget: plan around everything in the
                world, as :meth:`move_to` (not with ``linear``).

        Raises:
            RemoteError: the world refused it (``UnreachablePose``, ``ArmInMotion``,
                ``UnknownFrame``, ``linear`` with ``avoid_collisions``...); nothing moved
                and the current motion goes on.
            RemotePlanningFailed: with ``avoid_collisions``, no plan; nothing moved.
        """
        linear = flag(linear, "linear")
        planning, work_s = planning_request(avoid_collisions, clearance_m, timeout_s, budget)
        pin = sys.modules.get("pinocchio")  # a pinocchio.SE3 exists only once it is loaded
        if pin is not None and isinstance(pose, pin.SE3):
            pose = pose.homogeneous  # the world checks it is a rigid transform
        values = self._vector(pose, "a pose must be a 4x4 matrix or (x, y, z) of numbers")
        key = "position" if np.ndim(pose) == 1 else "pose"
        args = {"name": self._name, key: values, "frame": frame, "link": link, "linear": linear}
        args |= planning
        return float(self._client.call("move_pose", args, work_s=work_s)["duration_s"])

    def wait(self, timeout: float = WAIT_TIMEOUT_S) -> JointState:
        """Block until the motion is over and the arm holds its target; return its state.

        Raises:
            RemoteError: the arm stopped on a contact, faulted or left the world.
            RequestTimeout: still moving after ``timeout`` [s of wall time].
            InvalidNumber: ``timeout`` is not in [0, 600] s (nothing is sent).
        """
        number_ranges.WAIT_TIMEOUT_S.check(timeout, f"{self._name}: wait timeout")
        args = {"name": self._name, "timeout_s": timeout}
        # The world answers within ``timeout``; the margin lets its answer arrive.
        result = self._client.call("wait", args, timeout=timeout + WAIT_REPLY_MARGIN_S)
        state: JointState = decode_message("JointState", result["joint_state"])
        return state

    def reset_stop(self) -> None:
        """Accept commands again after a protective stop."""
        self._client.call("reset", {"name": self._name, "stop_only": True})

    def reset(self) -> None:
        """Leave ``error`` (controllers restart at the current pose) and any stop."""
        self._client.call("reset", {"name": self._name, "stop_only": False})

    def _describe(self) -> dict[str, Any]:
        description: dict[str, Any] = self._client.call("arm", {"name": self._name})
        return description

    def _vector(self, positions: Positions | Any, problem: str | None = None) -> list[float]:
        try:
            if not all_real(positions):  # not text, bool, complex or None (as in the world)
                raise ValueError(positions)
            values: list[float] = np.asarray(positions, dtype=float).reshape(-1).tolist()
        except ValueError:
            joints = ", ".join(self._joint_names)
            problem = problem or f"targets must be numbers, one per joint: {joints}"
            raise ArmfleetError(f"{self._name}: {problem}") from None
        return values

    def __repr__(self) -> str:
        return f"RemoteArm({self._name!r}, model={self._model!r}, pose={self._pose})"
