"""The position controller a ``tool_servo`` action needs: one the arm follows within a
few control periods.

The shipped ``position_controller`` plans its jerk-limited motions gently (5 rad/s^2,
50 rad/s^3 on every joint): from rest a joint moves 7e-5 rad in a 20 ms control period,
and reaching the speed the largest actions ask for takes ~12 periods (measured in
docs/envs.md, "Baseline"). A policy that sends a new small move every period then hardly
moves the arm. With ``action_kind="tool_servo"`` the environment gives its arms
:data:`SERVO_LIMITS` instead, the Franka Panda's own joint limits (15 rad/s^2 and
7,500 rad/s^3, from its datasheet): 1 cm tool0 commands from rest move tool0 1.8, 4.2,
then 5.4 mm in every 20 ms period. Everything else of the controller (gains, stops,
velocity limits) is the spec's.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from armfleet.spec import FleetSpec
from armfleet.spec.fleet_spec import ArmSpec, ControllerConfig

POSITION_CONTROLLER = "position_controller"
#: Planning limits of every joint under ``tool_servo`` actions: the Panda's datasheet
#: acceleration [rad/s^2] and jerk [rad/s^3] limits (its joints 1 and 5).
SERVO_LIMITS: Mapping[str, float] = {
    "max_acceleration_rad_s2": 15.0,
    "max_jerk_rad_s3": 7500.0,
}


def servo_spec(spec: FleetSpec) -> FleetSpec:
    """``spec`` with every arm's position controller planning with :data:`SERVO_LIMITS`
    (on top of the arm's own controller file and overrides)."""
    return dataclasses.replace(spec, arms=tuple(_servo_arm(arm) for arm in spec.arms))


def _servo_arm(arm: ArmSpec) -> ArmSpec:
    config = arm.controllers.get(POSITION_CONTROLLER, ControllerConfig())
    config = dataclasses.replace(config, parameters={**config.parameters, **SERVO_LIMITS})
    return dataclasses.replace(arm, controllers={**arm.controllers, POSITION_CONTROLLER: config})
