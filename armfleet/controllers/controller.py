"""Base of every controller: a lifecycle and a rate, as in ros2_control."""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from armfleet.controllers.parameters import ParameterSpec, load_parameters
from armfleet.errors import ArmfleetError
from armfleet.kinematics import ArmKinematics
from armfleet.physics.arm_body import ArmBody
from armfleet.runtime.bus import Bus


class LifecycleState(enum.Enum):
    UNCONFIGURED = "unconfigured"
    INACTIVE = "inactive"
    ACTIVE = "active"


class LifecycleError(ArmfleetError):
    """A lifecycle transition that is not allowed from the current state."""


@dataclass(frozen=True)
class ArmContext:
    """What a controller of one arm can reach: its body, model, bus and clock.

    Attributes:
        name: arm name, also its namespace (``/<name>``).
        body: the arm's joints in the physics engine.
        kinematics: the arm's Pinocchio model.
        bus: the world's bus.
        dt: physics step [s].
        compiled: step references and control laws in compiled code where it is built
            (``World(compiled_control=...)``).
    """

    name: str
    body: ArmBody
    kinematics: ArmKinematics
    bus: Bus
    dt: float
    compiled: bool = True

    def topic(self, relative: str) -> str:
        """``/<name>/<relative>``."""
        return f"/{self.name}/{relative}"


class Controller(ABC):
    """A controller of one arm, updated by its arm's controller manager.

    Subclasses define :attr:`type_name`, :attr:`parameter_schema` (which must
    include ``<...>_rate_hz`` as :attr:`rate_parameter`) and :meth:`update`.
    """

    type_name: ClassVar[str]
    parameter_schema: ClassVar[tuple[ParameterSpec, ...]]
    rate_parameter: ClassVar[str]
    #: Whether it writes commands (stopped when the arm faults) or only reads.
    writes_commands: ClassVar[bool] = False

    def __init__(
        self,
        arm: ArmContext,
        parameter_file: Path | None = None,
        overrides: Mapping[str, Any] | None = None,
    ) -> None:
        self.arm = arm
        self._parameter_file = parameter_file
        self._overrides = dict(overrides or {})
        self._state = LifecycleState.UNCONFIGURED
        self.parameters: dict[str, float | bool] = {}
        self.period_steps = 1
        #: Where :meth:`fail` reports to (set by the controller manager that loads it).
        self.on_failure: Callable[[Controller, Exception], None] | None = None

    @property
    def name(self) -> str:
        return self.type_name

    @property
    def state(self) -> LifecycleState:
        return self._state

    def configure(self) -> None:
        """unconfigured -> inactive: read and validate parameters, set up."""
        self._require(LifecycleState.UNCONFIGURED, "configure")
        self.parameters = load_parameters(
            self.type_name, self.parameter_schema, self._parameter_file, self._overrides
        )
        rate_hz = float(self.parameters[self.rate_parameter])
        self.period_steps = max(1, round(1.0 / (rate_hz * self.arm.dt)))
        self.on_configure()
        self._state = LifecycleState.INACTIVE

    def activate(self) -> None:
        """inactive -> active: start reading and writing."""
        self._require(LifecycleState.INACTIVE, "activate")
        self.on_activate()
        self._state = LifecycleState.ACTIVE

    def cleanup(self) -> None:
        """inactive -> unconfigured: release what configure set up (subscriptions, ...)."""
        self._require(LifecycleState.INACTIVE, "clean up")
        self.on_cleanup()
        self._state = LifecycleState.UNCONFIGURED

    def deactivate(self) -> None:
        """active -> inactive."""
        self._require(LifecycleState.ACTIVE, "deactivate")
        self.on_deactivate()
        self._state = LifecycleState.INACTIVE

    def fail(self, exc: Exception) -> None:
        """Report that this controller broke outside its update (e.g. in its own command
        subscription): its manager puts the arm in ``error``, as for a failed update.

        Raises:
            Exception: ``exc`` itself, if no manager has loaded this controller.
        """
        if self.on_failure is None:
            raise exc
        self.on_failure(self, exc)

    @property
    def period(self) -> float:
        """Time between updates [s]."""
        return self.period_steps * self.arm.dt

    def on_configure(self) -> None:  # noqa: B027 - optional hook
        """Hook: set up from :attr:`parameters`."""

    def on_cleanup(self) -> None:  # noqa: B027 - optional hook
        """Hook: undo :meth:`on_configure`."""

    def on_activate(self) -> None:  # noqa: B027 - optional hook
        """Hook: claim interfaces."""

    def on_deactivate(self) -> None:  # noqa: B027 - optional hook
        """Hook: release interfaces."""

    @abstractmethod
    def update(self, stamp: float) -> None:
        """One control cycle at simulated time ``stamp`` [s]; runs only while active."""

    def _require(self, state: LifecycleState, transition: str) -> None:
        if self._state is not state:
            raise LifecycleError(
                f"{self.arm.name}/{self.name}: cannot {transition} from {self._state.value} "
                f"(needs {state.value})"
            )
