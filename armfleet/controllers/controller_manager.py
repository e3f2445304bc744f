"""One controller manager per arm: loads its controllers and updates them in order."""

from __future__ import annotations

from armfleet.controllers.controller import Controller, LifecycleState
from armfleet.errors import ArmfleetError


class ControllerManager:
    """The controllers of one arm, updated once per physics step at their own rates."""

    def __init__(self, arm_name: str) -> None:
        self._arm_name = arm_name
        self._controllers: dict[str, Controller] = {}
        self._active: list[Controller] = []

    @property
    def controllers(self) -> dict[str, Controller]:
        return dict(self._controllers)

    def load(self, controller: Controller) -> Controller:
        """Add ``controller`` (unconfigured) under its name."""
        if controller.name in self._controllers:
            raise ArmfleetError(f"{self._arm_name}: controller {controller.name} already loaded")
        self._controllers[controller.name] = controller
        return controller

    def activate(self, name: str) -> None:
        """Configure if needed, then activate the controller ``name``."""
        controller = self._controllers[name]
        if controller.state is LifecycleState.UNCONFIGURED:
            controller.configure()
        controller.activate()
        self._active = [c for c in self._controllers.values() if c.state is LifecycleState.ACTIVE]

    def deactivate(self, name: str) -> None:
        self._controllers[name].deactivate()
        self._active = [c for c in self._controllers.values() if c.state is LifecycleState.ACTIVE]

    def shutdown(self) -> None:
        """Deactivate and clean up every controller (the arm is leaving the world)."""
        for controller in reversed(list(self._controllers.values())):
            if controller.state is LifecycleState.ACTIVE:
                controller.deactivate()
            if controller.state is LifecycleState.INACTIVE:
                controller.cleanup()
        self._active = []

    def update(self, stamp: float, step_index: int) -> None:
        """Update every active controller whose period divides ``step_index``, in load order."""
        for controller in self._active:
            if step_index % controller.period_steps == 0:
                controller.update(stamp)
