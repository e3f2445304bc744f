"""The handle users hold for an arm's gripper: ``arm.gripper.close()``, ``.open()``, ``.width``."""

from __future__ import annotations

from armfleet import topics
from armfleet.checks.real_numbers import STAMP_VALID, real_number
from armfleet.controllers.gripper_controller import GripperController
from armfleet.messages import GripperCommand, GripperMode, GripperState
from armfleet.runtime.bus import Bus
from armfleet.runtime.lifetime import Lifetime, while_alive


class Gripper:
    """The fingers of one arm, driven by its ``gripper_controller``.

    Commands return at once and go out on ``/<arm>/gripper_controller/commands``;
    step the world to see them carried out. Invalid ones raise
    :class:`armfleet.errors.GripperCommandError` (out of range, not finite) or
    :class:`armfleet.errors.InvalidNumber` (not a number: text, bool, None) and
    change nothing.
    Like its arm, it raises :class:`~armfleet.errors.UnknownArm` once the arm is
    removed and :class:`~armfleet.errors.WorldClosed` once the world is closed.
    """

    def __init__(
        self, arm: str, controller: GripperController, bus: Bus, lifetime: Lifetime
    ) -> None:
        self._arm = arm
        self._controller = controller
        self._bus = bus
        self._topic = topics.gripper_commands(arm)
        self._lifetime = lifetime

    @property
    def lifetime(self) -> Lifetime:
        """Its arm's: ended once the arm is removed or its world closed."""
        return self._lifetime

    @while_alive
    def open(self, *, force: float | None = None) -> None:
        """Open to the widest width."""
        self.move_to(self._controller.max_width, force=force)

    @while_alive
    def move_to(self, width: float, *, force: float | None = None) -> None:
        """Go to the opening ``width`` [m], pushing with at most ``force`` [N] per finger."""
        valid = f"a width in [0, {self.max_width:g}] m"
        number = real_number(width, f"{self._arm}: gripper width", valid, finite=False)
        self._send(GripperCommand(number, False, self._force(force)))

    @while_alive
    def close(self, force: float | None = None) -> None:
        """Close until blocked, then press with ``force`` [N] per finger (the
        ``grasp_force_n`` parameter by default)."""
        self._send(GripperCommand(0.0, True, self._force(force)))

    def _force(self, force: float | None) -> float:
        if force is None:
            return min(float(self._controller.parameters["grasp_force_n"]), self.max_force)
        valid = f"a force in (0, {self.max_force:g}] N"
        return real_number(force, f"{self._arm}: gripper force", valid, finite=False)

    def _send(self, command: GripperCommand) -> None:
        self._controller.check(command)
        self._bus.publish(self._topic, command)

    @property
    @while_alive
    def width(self) -> float:
        """Measured opening between the finger pads [m]."""
        return self._controller.width

    @property
    def max_width(self) -> float:
        """Widest opening [m]."""
        return self._controller.max_width

    @property
    def max_force(self) -> float:
        """Strongest force a finger can press with [N] (its URDF effort limit)."""
        return self._controller.max_force

    @property
    @while_alive
    def force(self) -> float:
        """Force each finger presses with now [N] (positive closing)."""
        return self._controller.force

    @property
    @while_alive
    def mode(self) -> GripperMode:
        return self._controller.mode

    @property
    @while_alive
    def holding(self) -> bool:
        """Whether the fingers squeeze something both of them touch."""
        return self._controller.holding

    @property
    @while_alive
    def is_moving(self) -> bool:
        """Whether the fingers are still on their way (to a width, or closing)."""
        return self._controller.mode in (GripperMode.MOVING, GripperMode.CLOSING)

    @while_alive
    def state(self, stamp: float = 0.0) -> GripperState:
        """The gripper's state (as published on ``/<arm>/gripper_controller/state``),
        stamped ``stamp`` [s of simulated time].

        Raises:
            InvalidNumber: ``stamp`` is not a finite number >= 0 (text, bool, None).
        """
        stamp = real_number(stamp, f"{self._arm}: gripper stamp", STAMP_VALID, low=0.0)
        return self._controller.gripper_state(stamp)

    def __repr__(self) -> str:
        controller = self._controller  # a removed arm's gripper still prints
        return f"Gripper(width={controller.width:.4f} m, mode={controller.mode.value!r})"
