"""The stages an arm goes through before the next one starts, reported on ``/bringup``.

spawned -> joint_state_broadcaster active (first joint state seen) ->
position_controller active -> ready (holding its pose for HOLD_STEPS steps).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from armfleet import topics
from armfleet.errors import BringupError
from armfleet.messages import BringupEvent, BringupStage, JointState

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.world import World

logger = logging.getLogger("armfleet")

#: Simulated time an arm may take to publish its first joint state / to hold [s].
BROADCASTER_TIMEOUT_S = 1.0
HOLD_TIMEOUT_S = 2.0
#: Consecutive steps holding within ``hold_tolerance_rad`` that make an arm ready. Every
#: step of a bring-up steps the whole world, so for a fleet this is most of its
#: bring-up time (10 steps: 30 Pandas in under 1 s).
HOLD_STEPS = 10


def bring_up(world: World, arm: Arm, started: float, on_ready: Callable[[Arm], None]) -> None:
    """Take ``arm`` (loaded, braked, controllers configured) to ready, stepping ``world``.

    Args:
        started: ``time.perf_counter()`` when the arm's bring-up began.
        on_ready: called just before the ready event (e.g. to show it in the viewer).
    """
    _report(world, arm.name, BringupStage.SPAWNED, started)
    _activate_broadcaster(world, arm)
    _report(world, arm.name, BringupStage.BROADCASTER_ACTIVE, started)
    arm.controller_manager.activate("position_controller")
    if arm.gripper_controller is not None:
        arm.controller_manager.activate(arm.gripper_controller.name)
    _report(world, arm.name, BringupStage.CONTROLLER_ACTIVE, started)
    _wait_holding(world, arm)
    on_ready(arm)
    _report(world, arm.name, BringupStage.READY, started)


def _activate_broadcaster(world: World, arm: Arm) -> None:
    seen: list[JointState] = []
    subscription = world.bus.subscribe(topics.joint_states(arm.name), seen.append)
    try:
        arm.controller_manager.activate("joint_state_broadcaster")
        deadline = world.time + BROADCASTER_TIMEOUT_S
        while not seen:
            if world.time >= deadline:
                raise BringupError(f"{arm.name}: no joint state within {BROADCASTER_TIMEOUT_S} s")
            world.step()
    finally:
        subscription.cancel()


def _wait_holding(world: World, arm: Arm) -> None:
    deadline = world.time + HOLD_TIMEOUT_S
    holding = 0
    while holding < HOLD_STEPS:
        if world.time >= deadline:
            raise BringupError(
                f"{arm.name}: not holding its pose after {HOLD_TIMEOUT_S} s "
                f"(tracking error {arm.position_controller.tracking_error:.3g} rad)"
            )
        world.step()
        holding = holding + 1 if arm.position_controller.is_holding else 0


def _report(world: World, arm: str, stage: BringupStage, started: float) -> None:
    logger.info("%s: %s", arm, stage.value)
    world.bus.publish(
        topics.BRINGUP, BringupEvent(arm, stage, world.time, time.perf_counter() - started)
    )
