"""One controller manager per arm: updates its controllers in order and contains their faults.

A controller that raises, or torques that are not finite, put only this arm in
``error``: the command-writing controllers stop, the brakes hold the joints,
read-only controllers (the broadcaster) keep reporting, and the rest of the
world steps on. :meth:`ControllerManager.reset` brings the arm back.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

from armfleet.controllers.controller import ArmContext, Controller, LifecycleState
from armfleet.errors import ArmfleetError

logger = logging.getLogger("armfleet")


class ControllerManager:
    """The controllers of one arm, updated once per physics step at their own rates.

    Args:
        arm: the arm the controllers drive.
        on_fault: called with the reason when the arm goes to ``error``.
    """

    def __init__(self, arm: ArmContext, on_fault: Callable[[str], None] | None = None) -> None:
        self._arm = arm
        self._on_fault = on_fault
        self._controllers: dict[str, Controller] = {}
        self._running: list[Controller] = []
        self._fault: str | None = None
        #: Changes whenever the running controllers do (for callers that cache them).
        self.version = 0

    @property
    def controllers(self) -> dict[str, Controller]:
        return dict(self._controllers)

    @property
    def fault(self) -> str | None:
        """Why the arm is in ``error``, or None."""
        return self._fault

    def load(self, controller: Controller) -> Controller:
        """Add ``controller`` (unconfigured) under its name."""
        if controller.name in self._controllers:
            raise ArmfleetError(f"{self._arm.name}: controller {controller.name} already loaded")
        self._controllers[controller.name] = controller
        controller.on_failure = self.fail_controller
        return controller

    def activate(self, name: str) -> None:
        """Configure if needed, then activate the controller ``name``."""
        controller = self._controllers[name]
        if controller.state is LifecycleState.UNCONFIGURED:
            controller.configure()
        controller.activate()
        self._refresh()

    def deactivate(self, name: str) -> None:
        self._controllers[name].deactivate()
        self._refresh()

    def shutdown(self) -> None:
        """Deactivate and clean up every controller (the arm is leaving the world)."""
        for controller in reversed(list(self._controllers.values())):
            if controller.state is LifecycleState.ACTIVE:
                controller.deactivate()
            if controller.state is LifecycleState.INACTIVE:
                controller.cleanup()
        self._running = []
        self.version += 1

    @property
    def running(self) -> tuple[Controller, ...]:
        """The controllers updated at each step (their rates permitting), in load order."""
        return tuple(self._running)

    def update(self, stamp: float, step_index: int) -> None:
        """Update every running controller whose period divides ``step_index``, in load order."""
        for controller in self._running:
            if step_index % controller.period_steps == 0:
                try:
                    controller.update(stamp)
                except Exception as exc:  # contain it to this arm
                    self.fail_controller(controller, exc)
                    return
        self.check_efforts()

    def fail_controller(self, controller: Controller, exc: Exception) -> None:
        """Put the arm in ``error`` because ``controller`` raised ``exc`` (in its update, or
        in its own command subscription)."""
        self._fail(f"{controller.name} raised {type(exc).__name__}: {exc}", controller)

    def check_efforts(self) -> None:
        """Put the arm in ``error`` if its effort commands are not all finite."""
        effort = self._arm.body.effort_command
        # A dot product is NaN or inf whenever an element is (and cheaper than isfinite().all()).
        if self._fault is None and not math.isfinite(effort.dot(effort)):
            self._fail("position_controller produced non-finite torques", None)

    def reset(self) -> None:
        """Leave ``error``: restart the stopped controllers holding the current pose."""
        if self._fault is None:
            return
        for controller in self._controllers.values():
            if controller.state is LifecycleState.ACTIVE and controller not in self._running:
                controller.deactivate()
                controller.activate()
        self._fault = None
        self._refresh()
        logger.info("%s: reset from error", self._arm.name)

    def _fail(self, reason: str, culprit: Controller | None) -> None:
        self._fault = reason
        self._arm.body.engage_brakes()
        self._running = [c for c in self._running if not c.writes_commands and c is not culprit]
        self.version += 1
        logger.error("%s: error: %s", self._arm.name, reason)
        if self._on_fault is not None:
            self._on_fault(reason)

    def _refresh(self) -> None:
        active = [c for c in self._controllers.values() if c.state is LifecycleState.ACTIVE]
        self._running = (
            active if self._fault is None else [c for c in active if not c.writes_commands]
        )
        self.version += 1
