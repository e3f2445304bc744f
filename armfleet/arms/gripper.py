"""The handle users hold for an arm's gripper: ``arm.gripper.close()``, ``.open()``, ``.width``."""

from __future__ import annotations

from armfleet import topics
from armfleet.checks.real_numbers import STAMP_VALID, real_number
from armfleet.controllers.gripper_controller import GripperController
from armfleet.messages import GripperCommand, GripperMode, GripperState
from armfleet.runtime.bus import Bus
from armfleet.runtime.lifetime import Lifetime, while_alive


class Gripper:
    """The fingers (or jaws) of one arm, driven by its ``gripper_controller``.

    Widths and forces are in the gripper's own units: for prismatic fingers the opening
    between the pads [m] and the force [N]; for revolute jaws (SO-100's) the jaw's angle
    [rad] and its torque [N m] (see :mod:`armfleet.controllers.gripper_controller`).

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
        """Go to the opening ``width`` [m, or rad], pushing with at most ``force`` [N, or
        N m] per finger."""
        controller = self._controller
        unit = controller.width_unit
        valid = f"a width in [{controller.min_width:g}, {self.max_width:g}] {unit}"
        number = real_number(width, f"{self._arm}: gripper width", valid, finite=False)
        self._send(GripperCommand(number, False, self._force(force)))

    @while_alive
    def close(self, force: float | None = None) -> None:
        """Close until blocked, then press with ``force`` [N, or N m] per finger (the
        ``grasp_force_n`` parameter by default; ``grasp_torque_n_m`` for revolute jaws)."""
        self._send(GripperCommand(0.0, True, self._force(force)))

    def _force(self, force: float | None) -> float:
        if force is None:
            return min(self._controller.default_force, self.max_force)
        valid = f"a force in (0, {self.max_force:g}] {self._controller.force_unit}"
        return real_number(force, f"{self._arm}: gripper force", valid, finite=False)

    def _send(self, command: GripperCommand) -> None:
        self._controller.check(command)
        self._bus.publish(self._topic, command)

    @property
    @while_alive
    def width(self) -> float:
        """Measured opening between the finger pads [m] (revolute jaws: angle [rad])."""
        return self._controller.width

    @property
    def max_width(self) -> float:
        """Widest opening [m, or rad]."""
        return self._controller.max_width

    @property
    def min_width(self) -> float:
        """Narrowest opening [m, or rad]: 0 for fingers, the jaw's lower limit for jaws."""
        return self._controller.min_width

    @property
    def width_unit(self) -> str:
        """Unit of widths: ``m`` for prismatic fingers, ``rad`` for revolute jaws."""
        return self._controller.width_unit

    @property
    def force_unit(self) -> str:
        """Unit of forces: ``N`` for prismatic fingers, ``N m`` for revolute jaws."""
        return self._controller.force_unit

    @property
    def max_force(self) -> float:
        """Strongest force a finger can press with [N, or N m] (its URDF effort limit)."""
        return self._controller.max_force

    @property
    @while_alive
    def force(self) -> float:
        """Force each finger presses with now [N, or N m] (positive closing)."""
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
