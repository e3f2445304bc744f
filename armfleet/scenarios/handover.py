"""The handover scenario: bob picks a bar from a table, hands it to toby in mid-air, and
toby puts it on the mat (launch_specs/handover.yaml; examples/handover.py shows it).

Grasps are planned from the bar's pose on /tf (where it really is), so the bar may start
anywhere near its spot; the transfers (to the bar, to the handover point, to the mat,
home) are planned around the tables, the other arm and the bar (``avoid_collisions``);
only the last few centimetres to and from a grasp are straight moves, since a plan keeps
1 cm from everything and cannot end with the fingers round the bar.

As a sweep task, :func:`handover` reports success and the placement error; the spec's
``sweep:`` section moves and turns the bar per run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armfleet.arms.arm import Arm
from armfleet.motion.move_options import SWEEP_BUDGET
from armfleet.world import World

GRASP_FROM_CENTRE_M = 0.07  # bob holds the bar's -x end, toby its +x end
HANDOVER_AT_M = (0.5, 0.0, 0.40)  # the bar's centre while it changes hands
ABOVE_M = 0.10  # approach and leave every grasp from this high
MAT_TO_BAR_CENTRE_M = 0.001 + 0.02  # half the mat + half the bar
TOLERANCE_M = 0.02


def frame(xyz: tuple[float, float, float], yaw: float = 0.0) -> np.ndarray:
    """4x4 pose at ``xyz`` [m], turned by ``yaw`` [rad] about z."""
    pose = np.eye(4)
    pose[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    pose[:3, 3] = xyz
    return pose


def grasp(bar: np.ndarray, end: int) -> np.ndarray:
    """Gripper (tcp) pose holding ``bar`` at its ``end`` (-1 or +1), from above, facing it."""
    tcp = np.diag([-end, end, -1.0, 1.0])  # z down, fingers closing across the bar
    tcp[0, 3] = end * GRASP_FROM_CENTRE_M
    return bar @ tcp


def lifted(pose: np.ndarray, height: float = ABOVE_M) -> np.ndarray:
    raised = pose.copy()
    raised[2, 3] += height
    return raised


@dataclass
class Watch:
    """What is checked at every step between the pick and the place."""

    picked: bool = False
    placed: bool = False
    steps_unheld: int = 0
    arm_contacts: int = 0
    lowest_bar_z_m: float = math.inf

    def __call__(self, world: World) -> None:
        self.arm_contacts += "toby" in world.contacts.touching_bodies("bob")
        if self.picked and not self.placed:
            held = world.arm("bob").gripper.holding or world.arm("toby").gripper.holding
            self.steps_unheld += not held
            self.lowest_bar_z_m = min(self.lowest_bar_z_m, world.object("bar").position[2])


def hand_over(world: World, *, realtime: bool = False, budget: int | None = None) -> Watch:
    """Run the handover in ``world`` (launched from handover.yaml); return what was seen.

    Each planned move has the default time budget, or ``budget`` planner iterations
    (then the same plans on any machine under any load)."""
    bob, toby = world.arm("bob"), world.arm("toby")
    watch = Watch()

    def wait(seconds: float) -> None:
        world.run(seconds, realtime=realtime, on_step=watch)

    def go(arm: Arm, pose: np.ndarray) -> None:
        """A planned move around everything in the world (the other arm included)."""
        wait(arm.move_to_pose(pose, link="tcp", avoid_collisions=True, budget=budget) + 0.2)

    def straight(arm: Arm, pose: np.ndarray) -> None:
        wait(arm.move_to_pose(pose, link="tcp", linear=True) + 0.2)

    def bar() -> np.ndarray:
        return world.tf.lookup("world", "bar")

    for arm in (bob, toby):
        arm.gripper.open()
    wait(0.5)
    # Bob picks the bar up by its -x end.
    pick = grasp(bar(), -1)
    go(bob, lifted(pick))
    straight(bob, pick)
    bob.gripper.close()
    wait(0.5)
    watch.picked = bob.gripper.holding
    straight(bob, lifted(pick))
    # ...holds it out to toby (the bar along x, between them)...
    bob_in_bar = np.linalg.solve(bar(), world.tf.lookup("world", "bob_tcp"))
    go(bob, frame(HANDOVER_AT_M) @ bob_in_bar)
    # ...toby takes it by the +x end, and bob lets go and steps back.
    take = grasp(bar(), +1)
    go(toby, lifted(take))
    straight(toby, take)
    toby.gripper.close()
    wait(0.5)
    bob.gripper.open()
    wait(0.5)
    straight(bob, lifted(world.tf.lookup("world", "bob_tcp")))
    bob.move_to(bob.description.home, avoid_collisions=True, budget=budget)  # toby plans round it
    # Toby puts the bar on the mat and steps back.
    toby_in_bar = np.linalg.solve(bar(), world.tf.lookup("world", "toby_tcp"))
    mat = world.tf.lookup("world", "mat")
    place = lifted(mat, MAT_TO_BAR_CENTRE_M + 0.002) @ toby_in_bar
    go(toby, lifted(place))
    straight(toby, place)
    watch.placed = True
    toby.gripper.open()
    wait(0.5)
    straight(toby, lifted(place))
    wait(toby.move_to(toby.description.home, avoid_collisions=True, budget=budget) + 0.5)
    return watch


def placement_error_m(world: World) -> float:
    """Distance of the bar's centre from its target: the mat's centre, 2.1 cm up [m]."""
    target = lifted(world.tf.lookup("world", "mat"), MAT_TO_BAR_CENTRE_M)[:3, 3]
    return float(np.linalg.norm(world.object("bar").position - target))


def handover(
    world: World,
    rng: np.random.Generator,
    *,
    tolerance_m: float = TOLERANCE_M,
    budget: int = SWEEP_BUDGET,
) -> dict[str, bool | int | float]:
    """The handover in ``world`` (launched from handover.yaml) as a sweep task.

    Args:
        rng: unused: the bar's start is drawn by the sweep (its ``randomize:``).
        tolerance_m: largest placement error of a success [m].
        budget: planner iterations of each planned move (so that the row is the same
            on any machine under any load).

    Returns:
        ``success`` (picked, placed within ``tolerance_m``, always held between, no
        contact between the arms, no protective stop), ``placement_error_m`` [m],
        ``picked``, ``steps_unheld``, ``arm_contacts`` and ``stops``.
    """
    del rng
    watch = hand_over(world, budget=budget)
    error = placement_error_m(world)
    stops = world.safety.stops
    success = (
        watch.picked
        and error <= tolerance_m
        and watch.steps_unheld == 0
        and watch.arm_contacts == 0
        and stops == 0
    )
    return {
        "success": success,
        "placement_error_m": error,
        "picked": watch.picked,
        "steps_unheld": watch.steps_unheld,
        "arm_contacts": watch.arm_contacts,
        "stops": stops,
    }
