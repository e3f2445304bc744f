"""The largest tracking error of some arms' position controllers, step by step.

After every step (``world.run(..., on_step=monitor.on_step)``) it reads each
controller's :attr:`~armfleet.controllers.PositionController.tracking_error`:
``max |q_ref - q|`` over the arm joints, the Ruckig reference for the current time
against the position measured at the end of the step, the pair the controller's next
update uses (and publishes on ``/<arm>/position_controller/state`` when someone
listens; reading it here costs half as much as listening: ~7 µs per arm and step).
A contact that pushes an arm off its reference shows in it, and so does the first
update of a protective stop, after which the reference restarts from the measured state.
"""

from __future__ import annotations

from collections.abc import Iterable

from armfleet.arms.arm import Arm
from armfleet.world import World


class TrackingMonitor:
    """Pass :meth:`on_step` to :meth:`armfleet.World.run` for the motions to watch.

    Args:
        arms: the arms to watch.
    """

    def __init__(self, arms: Iterable[Arm]) -> None:
        self._controllers = [arm.position_controller for arm in arms]
        #: Largest ``|q_ref - q|`` seen so far, over every watched joint [rad]; inf if a
        #: controller was inactive (its arm in error).
        self.max_error_rad = 0.0
        #: Steps seen.
        self.steps = 0

    def on_step(self, world: World) -> None:
        """Read every watched controller's tracking error (``world`` is unused)."""
        for controller in self._controllers:
            error = controller.tracking_error
            if error > self.max_error_rad:
                self.max_error_rad = error
        self.steps += 1
