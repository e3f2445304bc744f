"""Two arms swap cubes across one table, planning around each other, the post and the walls.

    python examples/shared_cell.py                  # in the viewer (open the printed URL)
    python examples/shared_cell.py --no-viewer      # headless; exit status 1 if a goal is missed
    python examples/shared_cell.py --cubes 6 --seed 3

The scene is launch_specs/shared_cell.yaml: bob at (0, 0) and toby at (0.9, 0) facing
each other over a table split by a post and two low walls. Bob's cubes start on his
half (x < 0.45 m) and end on toby's; toby's go the other way. The cubes are put
down with ``world.add_object`` (the spec's own four make way for them).

Every motion between table positions is planned (``avoid_collisions``). Picks and
places run in parallel: an arm plans while the other moves, and the planner checks the
plan in time against the other arm's motion. The crossings are planned jointly, in the
two arms' 14-joint space (``world.plan`` then ``world.execute``, which is what
``world.move_together(..., avoid_collisions=True)`` does), because each arm's goal is
where the other arm is. The straight moves down to a cube and back up (MoveIt's
approach and retreat; a plan keeps 1 cm from everything, so it cannot end with the
fingers round a cube) and opening a gripper are not planned: an arm starts one only
while the other arm stands still, so any plan made meanwhile sees it moving.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import NoReturn

import numpy as np

import armfleet
from armfleet.messages import CollisionReport
from armfleet.planning import PlanningFailed

CUBE_M = 0.04  # side of a cube
CUBE_KG = 0.1
CUBE_Z_M = 0.17  # a cube's centre resting on the table (top at 0.15 m)
MIDDLE_X_M = 0.45  # the table's middle line, between bob's half and toby's
#: Cube spots on bob's half (x, y) [m]; toby's are these turned 180 degrees about the
#: table's centre, as toby is bob turned. 11 cm apart across the fingers (open: 8 cm),
#: clear of the post and the walls. None at y = +0.16: toby's forearm, reaching down
#: there from its home posture's branch, touches the post (and bob's at toby's -0.16).
SPOTS_M = tuple((x, y) for x in (0.29, 0.37) for y in (-0.38, -0.27, -0.16, 0.27, 0.38))
MAX_CUBES = 2 * len(SPOTS_M)
ABOVE_M = 0.06  # approach and leave every cube from this high
JITTER_M, JITTER_DEG = 0.005, 10.0  # random start of each cube around its spot
TOLERANCE_M = 0.01  # a cube's centre ends this close to its spot (a quarter of its side)
#: Each finger's squeeze on a cube [N]. Planned moves pass their waypoints at speed: with the
#: gripper's default 20 N a cube pivoted between the pads on a turn and was set down tilted,
#: 19.6 mm off its spot (seed 1); 50 N holds it (0.4 mm), within the Panda's 100 N.
GRASP_FORCE_N = 50.0
GRIP_S = 0.5  # time for the fingers to close or open
SETTLE_S = 0.1  # wait after a motion's planned duration
POLL_S = 0.02  # how often a waiting arm looks again
RETRY_S = 0.25  # wait before planning again when the other arm is in the way
ATTEMPTS = 40  # plans tried for one motion before giving up
STEP_ASIDE_AFTER = 4  # refused plans after which a lone arm goes home first
PLANNING_TIMEOUT_S = 2.0  # per plan
DOWN = np.diag([1.0, -1.0, -1.0, 1.0])  # tcp z down, x along the frame's x
COLOURS = ((0.85, 0.2, 0.2, 1.0), (0.2, 0.6, 0.85, 1.0))  # bob's cubes, toby's cubes

#: A task yields the simulated time [s] to wait before it goes on.
Task = Iterator[float]


def frame(xyz: tuple[float, float, float], yaw: float = 0.0) -> np.ndarray:
    """4x4 pose at ``xyz`` [m], turned by ``yaw`` [rad] about z."""
    pose = np.eye(4)
    pose[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    pose[:3, 3] = xyz
    return pose


def lifted(pose: np.ndarray, height: float = ABOVE_M) -> np.ndarray:
    raised = pose.copy()
    raised[2, 3] += height
    return raised


def spot(side: str, index: int) -> np.ndarray:
    """The ``index``-th cube spot on ``side``'s half of the table (x, y) [m]."""
    x, y = SPOTS_M[index]
    return np.array([x, y] if side == "bob" else [2 * MIDDLE_X_M - x, -y])


@dataclass
class Cube:
    """A cube, the arm that moves it, and the spot where it must end."""

    name: str
    arm: str
    target: np.ndarray  # (x, y) [m]

    def error_m(self, world: armfleet.World) -> float:
        """Distance from the cube's centre to its target spot on the table [m]."""
        wanted = np.array([*self.target, CUBE_Z_M])
        return float(np.linalg.norm(world.object(self.name).position - wanted))


@dataclass
class Tally:
    """Contacts seen on /collisions, protective stops, and the plans made."""

    arm_arm: int = 0  # new contacts between two arms
    arm_obstacle: int = 0  # new contacts of an arm with a static object or the floor
    replans: int = 0  # plans refused (the other arm in the way), then tried again
    step_asides: int = 0  # times an arm went home to let the other one pass
    planning_ms: list[float] = field(default_factory=list)
    _touching: set[tuple[str, str]] = field(default_factory=set)

    def on_collisions(self, world: armfleet.World, report: CollisionReport) -> None:
        """Count each contact once, when it starts (a /collisions subscriber)."""
        arms, objects = world.arms, world.objects
        now: set[tuple[str, str]] = set()
        for contact in report.contacts:
            a, b = contact.body_a, contact.body_b
            if a not in arms and b not in arms:
                continue
            other = b if a in arms else a
            if other in objects and not objects[other].is_static:
                continue  # a cube: what the arms are for
            now.add(contact.pair)
            if contact.pair in self._touching:
                continue
            if a in arms and b in arms:
                self.arm_arm += a != b
            else:
                self.arm_obstacle += 1
        self._touching = now


class Cell:
    """The shared cell: its world, the cubes and the arms' tasks."""

    def __init__(self, world: armfleet.World, tally: Tally, *, realtime: bool) -> None:
        self.world = world
        self.tally = tally
        self.realtime = realtime

    # -- running tasks side by side --------------------------------------------------------
    def run(self, *tasks: Task) -> None:
        """Step the world until every task is done, resuming each when its wait is over."""
        world = self.world
        wake = {index: world.time for index in range(len(tasks))}
        while wake:
            for index in list(wake):
                if wake[index] <= world.time + world.dt / 2:
                    try:
                        wake[index] = world.time + next(tasks[index])
                    except StopIteration:
                        del wake[index]
            if wake:
                world.run(max(min(wake.values()) - world.time, world.dt), realtime=self.realtime)

    # -- motions ---------------------------------------------------------------------------
    def reach(self, arm: armfleet.Arm, pose: np.ndarray) -> np.ndarray:
        """Joint positions that put ``arm``'s tcp at ``pose``, on the branch of its home
        posture (elbow up, wrist as at home), so that the straight moves down from there
        stay on it. (A pose goal may be solved on any branch clear of collisions.)"""
        positions: np.ndarray = arm.solve_ik(pose, link="tcp", seed=arm.description.home)
        return positions

    def planned(self, goals: Mapping[str, np.ndarray | Sequence[float]]) -> Task:
        """Move the arms to ``goals`` (joint positions by arm name) around everything,
        planned jointly when there are several; try again while another arm is in the way.

        One arm refused :data:`STEP_ASIDE_AFTER` times goes home first: two arms that
        wait for each other (each one's goal where the other stands) would wait forever.
        """
        for attempt in range(ATTEMPTS):
            try:
                plan = self.world.plan(goals, timeout_s=PLANNING_TIMEOUT_S)
            except PlanningFailed:
                if attempt == ATTEMPTS - 1:
                    raise
                self.tally.replans += 1
                if attempt + 1 == STEP_ASIDE_AFTER and len(goals) == 1:
                    yield from self.step_aside(self.world.arm(next(iter(goals))))
                yield RETRY_S
                continue
            self.tally.planning_ms.append(plan.planning_time_s * 1000)
            yield self.world.execute(plan) + SETTLE_S
            return

    def step_aside(self, arm: armfleet.Arm) -> Task:
        """Take ``arm`` home (planned), out of the other arm's way, if a plan is found."""
        if np.allclose(arm.positions, arm.description.home, atol=1e-2):
            return
        try:
            plan = self.world.plan({arm.name: arm.description.home}, timeout_s=PLANNING_TIMEOUT_S)
        except PlanningFailed:
            return
        self.tally.step_asides += 1
        self.tally.planning_ms.append(plan.planning_time_s * 1000)
        yield self.world.execute(plan) + SETTLE_S

    def still_others(self, arm: armfleet.Arm) -> Task:
        """Wait until every other arm stands still."""
        while any(o.is_moving for o in self.world.arms.values() if o is not arm):
            yield POLL_S

    def straight(self, arm: armfleet.Arm, pose: np.ndarray) -> Task:
        """A straight tcp move, started while the other arm stands still."""
        yield from self.still_others(arm)
        yield arm.move_to_pose(pose, link="tcp", linear=True) + SETTLE_S

    def grip(self, arm: armfleet.Arm, close: bool) -> Task:
        if close:
            arm.gripper.close(GRASP_FORCE_N)  # the fingers only move inwards: no wait
        else:
            yield from self.still_others(arm)  # opening widens the hand
            arm.gripper.open()
        yield GRIP_S

    # -- pick and place --------------------------------------------------------------------
    def grasp(self, arm: armfleet.Arm, cube: Cube) -> np.ndarray:
        """Tcp pose holding ``cube`` from above, as the cube is now on /tf, turned by a
        multiple of 90 degrees to face the way the arm does."""
        pose = self.world.tf.lookup("world", cube.name)
        facing = math.radians(arm.pose.yaw_deg)
        turn = math.atan2(pose[1, 0], pose[0, 0]) - facing
        turn -= math.pi / 2 * round(turn / (math.pi / 2))
        x, y, z = pose[:3, 3]
        return frame((x, y, z), facing + turn) @ DOWN

    def pick(self, arm: armfleet.Arm, cube: Cube) -> Task:
        pose = self.grasp(arm, cube)
        yield from self.planned({arm.name: self.reach(arm, lifted(pose))})
        yield from self.straight(arm, pose)
        yield from self.grip(arm, close=True)
        yield from self.straight(arm, lifted(pose))

    def place_pose(self, arm: armfleet.Arm, cube: Cube) -> np.ndarray:
        """Tcp pose that sets the held ``cube`` down on its target spot."""
        world = self.world
        tcp = world.tf.lookup("world", f"{arm.name}_tcp")
        cube_in_tcp = np.linalg.solve(tcp, world.tf.lookup("world", cube.name))
        # the cube ends turned as it is in the hand (a multiple of 90 degrees from the
        # grasp), so that the hand ends facing the arm's way, as it picked
        turn = math.atan2(cube_in_tcp[1, 0], cube_in_tcp[0, 0])
        where = frame((*cube.target, CUBE_Z_M), math.radians(arm.pose.yaw_deg) + turn)
        pose: np.ndarray = where @ np.linalg.inv(cube_in_tcp)
        return pose

    def place(self, arm: armfleet.Arm, cube: Cube) -> Task:
        """Set the held ``cube`` down, resting on the table, and leave it."""
        pose = self.place_pose(arm, cube)  # again: the cube may have turned in the fingers
        yield from self.straight(arm, pose)
        yield from self.grip(arm, close=False)
        yield from self.straight(arm, lifted(pose))

    def place_and_pick(self, arm: armfleet.Arm, carried: Cube | None, cube: Cube | None) -> Task:
        """Put the ``carried`` cube down (if any), then pick ``cube`` (if any)."""
        if carried is not None:
            yield from self.place(arm, carried)
        if cube is not None:
            yield from self.pick(arm, cube)


def swap_spots(count: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    """Per round, bob's spot and toby's spot (indices in :data:`SPOTS_M`) whose cubes the
    arms swap. Toby's spot is on the other side of y = 0 from bob's, so the arms reach
    past each other, not into each other; the sides alternate while both have spots."""
    groups = [[i for i, (_, y) in enumerate(SPOTS_M) if (y > 0) == above] for above in (0, 1)]
    rounds = [list(zip(rng.permutation(g), rng.permutation(g), strict=True)) for g in groups]
    pairs: list[tuple[int, int]] = []
    while len(pairs) < (count + 1) // 2:
        for group in rounds:
            if group and len(pairs) < (count + 1) // 2:
                bob, toby = group.pop()
                pairs.append((int(bob), int(toby)))
    return pairs


def set_out_cubes(world: armfleet.World, count: int, rng: np.random.Generator) -> list[Cube]:
    """Put ``count`` cubes on the table, bob's (red) on his half and toby's (blue) on his,
    each with the spot where it must end; the spec's own cubes make way for them."""
    for name in [name for name in world.objects if name.startswith("cube_")]:
        world.remove_object(name)
    cubes: list[Cube] = []
    for bob_spot, toby_spot in swap_spots(count, rng):
        for arm, start, end in (("bob", bob_spot, toby_spot), ("toby", toby_spot, bob_spot)):
            if len(cubes) == count:
                break
            x, y = spot(arm, start) + rng.uniform(-JITTER_M, JITTER_M, 2)
            name = f"cube_{len(cubes) + 1}"
            world.add_object(
                name,
                "box",
                size=(CUBE_M, CUBE_M, CUBE_M),
                mass=CUBE_KG,
                color=COLOURS[arm == "toby"],
                at=(x, y, CUBE_Z_M),
                rpy_deg=(0.0, 0.0, rng.uniform(-JITTER_DEG, JITTER_DEG)),
            )
            cubes.append(Cube(name, arm, spot("toby" if arm == "bob" else "bob", end)))
    return cubes


def swap(cell: Cell, cubes: list[Cube], *, quiet: bool) -> None:
    """Move every cube to the other half, round by round: each arm puts down the cube it
    carried over and picks its next one while the other does the same; then both carry
    their cubes across together."""
    world = cell.world
    arms = {name: world.arm(name) for name in ("bob", "toby")}
    queues = {name: [c for c in cubes if c.arm == name] for name in arms}
    cell.run(*(cell.grip(arm, close=False) for arm in arms.values()))
    carried: dict[str, Cube] = {}  # arm -> the cube it holds over the cube's spot
    for rank in range(max(len(queue) for queue in queues.values()) + 1):
        batch = {name: queue[rank] for name, queue in queues.items() if rank < len(queue)}
        cell.run(*(cell.place_and_pick(arms[n], carried.get(n), batch.get(n)) for n in arms))
        if carried and not quiet:
            moved = ", ".join(
                f"{c.name} {c.error_m(world) * 1000:.1f} mm" for c in carried.values()
            )
            print(f"t = {world.time:6.1f} s: {moved} from its target", flush=True)
        carried = batch
        over = {
            n: cell.reach(arms[n], lifted(cell.place_pose(arms[n], c))) for n, c in batch.items()
        }
        if over:
            cell.run(cell.planned(over))
    cell.run(cell.planned({name: arm.description.home for name, arm in arms.items()}))


@dataclass(frozen=True)
class Outcome:
    """What one run achieved; :attr:`success` is the example's goal."""

    seed: int
    cubes: int
    placed: int  # cubes within TOLERANCE_M of their target spot
    worst_error_m: float
    arm_arm_contacts: int
    arm_obstacle_contacts: int
    stops: int
    replans: int
    step_asides: int
    plans: int
    median_planning_ms: float
    simulated_s: float
    wall_s: float  # of the work, after the launch
    gave_up: str = ""  # why the work stopped early (e.g. no plan in ATTEMPTS tries)

    @property
    def success(self) -> bool:
        return (
            not self.gave_up
            and self.placed == self.cubes
            and self.arm_arm_contacts == 0
            and self.arm_obstacle_contacts == 0
            and self.stops == 0
        )

    def __str__(self) -> str:
        lines = [
            f"cubes on the other half within {TOLERANCE_M * 1000:.0f} mm: "
            f"{self.placed}/{self.cubes} (worst {self.worst_error_m * 1000:.1f} mm)",
            f"contacts arm-arm: {self.arm_arm_contacts}, arm-obstacle: "
            f"{self.arm_obstacle_contacts}; protective stops: {self.stops}",
            f"plans: {self.plans} (median {self.median_planning_ms:.0f} ms), "
            f"refused and tried again: {self.replans}, arm went home to let the other "
            f"pass: {self.step_asides}",
            f"simulated {self.simulated_s:.1f} s in {self.wall_s:.1f} s (seed {self.seed})",
        ]
        if self.gave_up:
            lines.append(f"gave up: {self.gave_up}")
        lines.append("success" if self.success else "FAILED")
        return "\n".join(lines)


def work(
    world: armfleet.World,
    cubes: list[Cube],
    seed: int = 0,
    *,
    realtime: bool = False,
    quiet: bool = False,
) -> Outcome:
    """Swap ``cubes`` (set out by :func:`set_out_cubes`) in ``world`` and say how it went."""
    began = time.perf_counter()
    tally = Tally()
    world.bus.subscribe("/collisions", lambda report: tally.on_collisions(world, report))
    gave_up = ""
    try:
        swap(Cell(world, tally, realtime=realtime), cubes, quiet=quiet)
    except armfleet.ArmfleetError as exc:  # PlanningFailed after ATTEMPTS, a stopped arm
        gave_up = str(exc)
    errors = [cube.error_m(world) for cube in cubes]
    return Outcome(
        seed=seed,
        cubes=len(cubes),
        placed=sum(e <= TOLERANCE_M for e in errors),
        worst_error_m=max(errors),
        arm_arm_contacts=tally.arm_arm,
        arm_obstacle_contacts=tally.arm_obstacle,
        stops=world.safety.stops,
        replans=tally.replans,
        step_asides=tally.step_asides,
        plans=len(tally.planning_ms),
        median_planning_ms=float(np.median(tally.planning_ms)) if tally.planning_ms else 0.0,
        simulated_s=world.time,
        wall_s=time.perf_counter() - began,
        gave_up=gave_up,
    )


def run(cubes: int = 20, seed: int = 0, *, viewer: bool = False, quiet: bool = False) -> Outcome:
    """Launch the cell, swap ``cubes`` cubes (set out by ``seed``), and say how it went."""
    world = armfleet.launch("shared_cell", viewer=viewer)
    try:
        if viewer and world.viewer is not None:
            print(f"viewer: {world.viewer.url}", flush=True)
        placed = set_out_cubes(world, cubes, np.random.default_rng(seed))
        return work(world, placed, seed, realtime=viewer, quiet=quiet)
    finally:
        world.close()


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message}\n")


def count(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: a whole number in [low, high]."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = low - 1
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number in [{low}, {high}]")
        return value

    return parse


def main() -> None:
    parser = OneLineParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-viewer", action="store_true", help="run headless")
    parser.add_argument(
        "--cubes",
        type=count(1, MAX_CUBES),
        default=20,
        help=f"cubes to move, 1 to {MAX_CUBES}, one per spot (default 20)",
    )
    parser.add_argument(
        "--seed", type=count(0, 2**32 - 1), default=0, help="where the cubes start (default 0)"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    args = parser.parse_args()
    outcome = run(args.cubes, args.seed, viewer=not args.no_viewer, quiet=args.quiet)
    print(outcome)
    sys.exit(0 if outcome.success else 1)


if __name__ == "__main__":
    main()
