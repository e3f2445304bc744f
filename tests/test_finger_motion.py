"""A finger command is always taken, and never faults its arm (issue 28, item 11).

The state below is one random open/close commands at a 20 ms period reached (a fuzz of
the fingers' reference alone, 2,000 episodes of 200 commands): both Panda fingers
cruising closed at their 0.1 m/s limit, their motions ~5e-8 s apart, told to open.
Ruckig's synchronisation of the two fingers failed on it ("error in step 2"), and the
open command was lost (earlier, the arm faulted with ``gripper_controller raised
RuckigError``).
"""

from __future__ import annotations

import numpy as np
import pytest
import ruckig

import armfleet
from armfleet.messages import ArmMode

POSITION = (0.022783962463863966, 0.02278396743443854)
VELOCITY = (0.1, 0.09999996622338404)
ACCELERATION = (-1.6209256159527285e-14, -2.6574623177566536e-06)
#: Fingers are at rest within this of their target once the motion ends [m].
REST_TOLERANCE_M = 1e-3


def test_ruckig_alone_fails_to_synchronise_the_fingers_in_this_state() -> None:
    """The premise: this is the input Ruckig rejects (if a Ruckig release fixes it,
    the test below still holds)."""
    motion = ruckig.InputParameter(2)
    motion.current_position = list(POSITION)
    motion.current_velocity = list(VELOCITY)
    motion.current_acceleration = list(ACCELERATION)
    motion.target_position = [0.04, 0.04]
    motion.max_velocity = [0.1, 0.1]
    motion.max_acceleration = [2.0, 2.0]
    motion.max_jerk = [100.0, 100.0]
    with pytest.raises(ruckig.RuckigError, match="step 2"):
        ruckig.Ruckig(2, 0.001).calculate(motion, ruckig.Trajectory(2))


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "bindings"])
def test_open_while_the_fingers_cruise_closed_is_taken(compiled: bool) -> None:
    with armfleet.World(compiled_control=compiled) as world:
        arm = world.spawn("bob", "panda")
        arm.move_to(arm.positions + 0.3)  # the arm moving meanwhile
        controller = arm.gripper._controller
        assert controller.trajectory is not None
        trajectory = controller.trajectory
        arm.gripper.close()
        world.step()
        # The fingers' reference where the fuzz left it (closing at full speed).
        trajectory.position[:] = POSITION
        trajectory.velocity[:] = VELOCITY
        trajectory.acceleration[:] = ACCELERATION
        arm.gripper.open()
        assert controller.target_width == pytest.approx(arm.gripper.max_width)
        for _ in range(600):  # 0.6 s: the 0.2 s motion, and the fingers settling
            world.step()
        assert arm.mode is not ArmMode.ERROR, arm.mode
        assert not trajectory.moving
        np.testing.assert_allclose(trajectory.position, [0.04, 0.04], atol=1e-12)
        assert arm.gripper.width == pytest.approx(arm.gripper.max_width, abs=REST_TOLERANCE_M)
