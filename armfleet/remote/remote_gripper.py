"""A client's handle on an arm's gripper, shaped like :class:`armfleet.arms.gripper.Gripper`."""

from __future__ import annotations

from typing import Any

from armfleet.checks import number_ranges
from armfleet.checks.real_numbers import real_number
from armfleet.messages import GripperMode, GripperState
from armfleet.remote.service_caller import ServiceCaller
from armfleet.services.codec import decode_message

#: Default wait for the fingers to stop [s of wall time].
GRIP_WAIT_TIMEOUT_S = 10.0
#: Extra wait for the world's answer to a wait [s].
WAIT_REPLY_MARGIN_S = 2.0


class RemoteGripper:
    """The fingers of one arm of the world a :class:`Client` is connected to.

    Commands return once the world has accepted them (checked as in the world:
    a width or force out of range raises :class:`RemoteError` and changes nothing);
    :meth:`wait` blocks until the fingers stop. Every property asks the world.
    """

    def __init__(self, client: ServiceCaller, arm: str, description: dict[str, Any]) -> None:
        self._client = client
        self._arm = arm
        self._max_width = float(description["max_width"])
        self._max_force = float(description["max_force"])
        # Worlds before revolute jaws sent none of these: fingers, in metres and newtons.
        self._min_width = float(description.get("min_width", 0.0))
        self._width_unit = str(description.get("width_unit", "m"))
        self._force_unit = str(description.get("force_unit", "N"))

    @property
    def max_width(self) -> float:
        """Widest opening [m, or rad for revolute jaws]."""
        return self._max_width

    @property
    def min_width(self) -> float:
        """Narrowest opening [m, or rad for revolute jaws]."""
        return self._min_width

    @property
    def width_unit(self) -> str:
        """``m`` for prismatic fingers, ``rad`` for a revolute jaw."""
        return self._width_unit

    @property
    def max_force(self) -> float:
        """Strongest force a finger can press with [N, or N m for revolute jaws]."""
        return self._max_force

    def open(self, *, force: float | None = None) -> GripperState:
        """Open to the widest width; returns the state as the command started."""
        return self._grip("open", None, force)

    def close(self, force: float | None = None) -> GripperState:
        """Close until blocked, then press with ``force`` [N] per finger (the arm's
        ``grasp_force_n`` by default)."""
        return self._grip("close", None, force)

    def move_to(self, width: float, *, force: float | None = None) -> GripperState:
        """Go to the opening ``width`` [m, or rad], pushing with at most ``force`` [N, or
        N m] per finger."""
        return self._grip("width", width, force)

    def wait(self, timeout: float = GRIP_WAIT_TIMEOUT_S) -> GripperState:
        """Block until the fingers stop (at the width, closed, or squeezing something).

        Raises:
            RemoteError: the arm left the world.
            RequestTimeout: still moving after ``timeout`` [s of wall time].
            InvalidNumber: ``timeout`` is not in [0, 600] s (nothing is sent).
        """
        number_ranges.WAIT_TIMEOUT_S.check(timeout, f"{self._arm}: gripper wait timeout")
        args = {"name": self._arm, "timeout_s": timeout, "gripper": True}
        result = self._client.call("wait", args, timeout=timeout + WAIT_REPLY_MARGIN_S)
        return _state(result)

    @property
    def state(self) -> GripperState:
        """The gripper's state now (as on ``/<arm>/gripper_controller/state``)."""
        description = self._client.call("arm", {"name": self._arm})["gripper"]
        return _state(description)

    @property
    def width(self) -> float:
        """Measured opening between the finger pads [m]."""
        return self.state.width

    @property
    def mode(self) -> GripperMode:
        return self.state.mode

    @property
    def holding(self) -> bool:
        """Whether the fingers squeeze something both of them touch."""
        return self.state.holding

    @property
    def is_moving(self) -> bool:
        return self.state.mode in (GripperMode.MOVING, GripperMode.CLOSING)

    def _grip(self, action: str, width: float | None, force: float | None) -> GripperState:
        # Text, bool or None are refused here as in the world (InvalidNumber); a number
        # out of range goes to the world, which names the range.
        args: dict[str, Any] = {"name": self._arm, "action": action}
        if action == "width":
            valid = f"a width in [{self._min_width:g}, {self._max_width:g}] {self._width_unit}"
            args["width"] = real_number(width, f"{self._arm}: gripper width", valid, finite=False)
        if force is not None:
            valid = f"a force in (0, {self._max_force:g}] {self._force_unit}"
            args["force"] = real_number(force, f"{self._arm}: gripper force", valid, finite=False)
        return _state(self._client.call("grip", args))

    def __repr__(self) -> str:
        return f"RemoteGripper({self._arm!r})"


def _state(data: Any) -> GripperState:
    state: GripperState = decode_message("GripperState", data)
    return state
