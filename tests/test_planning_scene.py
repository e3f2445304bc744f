"""The planning scene is the world: its collision answer against PyBullet's own distances.

A scratch world of the shared cell (two Pandas 0.9 m apart over a table with a post, two
walls and four loose cubes) is snapshotted as the planner does; then, for a few hundred
configurations of both arms, the arms are put there in PyBullet (``resetJointState``,
no step) and PyBullet's ``getClosestPoints`` measures every pair that counts:

- between different bodies (arm and arm, arm and object, arm and floor), the pairs in
  which a link moves, against the clearance ``c``;
- within one arm, the link pairs the world counts as contacts (not adjacent, not ruled
  out by sampling: :func:`armfleet.physics.collision_filter.ignored_self_pairs`), against the
  arm's own margin ``min(c, 10 mm)``.

``CollisionChecker.valid`` must say False whenever PyBullet finds a pair closer than its
margin minus :data:`HULL_TOLERANCE_M`, and True whenever every pair is further than its
margin plus it. Measured here: PyBullet's distances are coal's minus 0 to 2.0 mm for
mesh pairs (each convex hull carries a 1 mm collision margin in Bullet) and within
0.8 mm for box pairs, so 2.5 mm covers the difference of the two engines' shapes and
nothing else.

Random configurations mostly collide deeply; the informative ones are near the margin.
So besides uniform samples, states are taken on lines from home to a random state, by
bisection on PyBullet's distance, just inside the clearance (5 mm into it, not touching)
and just outside it (5 mm beyond).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.messages import FloatArray
from armfleet.physics.collision_filter import ignored_self_pairs
from armfleet.physics.start_clearance import BodyKind
from armfleet.planning import FailureReason, PlanningFailed
from armfleet.planning.scene import SELF_CLEARANCE_M, CollisionChecker

#: Difference allowed between PyBullet's and the scene's shapes [m] (see the module doc).
HULL_TOLERANCE_M = 2.5e-3
#: How far inside / outside the margin the boundary states are taken [m].
BAND_M = 5e-3
#: Uniform random states, and lines from home on which boundary states are sought.
UNIFORM_STATES = 150
BOUNDARY_LINES = 100
#: Bisection steps per boundary state (2^-20 of a line of a few rad: micro-radians).
BISECTION_STEPS = 20
FLOOR = "ground"


@dataclass(frozen=True)
class Pair:
    """A pair of PyBullet links that counts, and its margin [m]."""

    body_a: int
    link_a: int
    body_b: int
    link_b: int
    margin: float
    names: tuple[str, str]


@dataclass(frozen=True)
class Measure:
    """PyBullet's verdict on one state: the smallest (distance - margin) [m], and the
    pairs closer than their margin minus the tolerance."""

    excess: float
    offending: tuple[tuple[str, str], ...]


def link_name(client: int, body: int, link: int) -> str:
    if link == -1:
        return str(p.getBodyInfo(body, physicsClientId=client)[0].decode())
    return str(p.getJointInfo(body, link, physicsClientId=client)[12].decode())


def moving_links(client: int, body: int) -> set[int]:
    """Links of ``body`` moved by some joint (read from PyBullet's own joint tree)."""
    moves: dict[int, bool] = {-1: False}
    for link in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, link, physicsClientId=client)
        moves[link] = info[2] != p.JOINT_FIXED or moves[info[16]]
    return {link for link, moved in moves.items() if moved}


def pybullet_joints(client: int, arm: armfleet.Arm) -> list[int]:
    """PyBullet's joint indices of ``arm.joint_names``, found by name."""
    body = arm.body.body_id
    index = {
        p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
        for j in range(p.getNumJoints(body, physicsClientId=client))
    }
    return [index[name] for name in arm.joint_names]


def solid_links(client: int, body: int) -> list[int]:
    links = [-1, *range(p.getNumJoints(body, physicsClientId=client))]
    return [link for link in links if p.getCollisionShapeData(body, link, physicsClientId=client)]


def counted_pairs(world: armfleet.World, clearance_m: float) -> list[Pair]:
    """Every PyBullet link pair the scene must answer for, with its margin."""
    client = world.physics_client
    self_margin = min(clearance_m, SELF_CLEARANCE_M)
    neighbours = world.contacts.neighbours()
    arm_bodies = [n for n in neighbours if n.kind is BodyKind.ARM]
    others = [n for n in neighbours if n.kind is not BodyKind.ARM]
    pairs: list[Pair] = []

    def add(a: int, la: int, b: int, lb: int, margin: float, names: tuple[str, str]) -> None:
        pairs.append(Pair(a, la, b, lb, margin, names))

    for index, arm in enumerate(arm_bodies):
        body = arm.body_id
        solid, moving = solid_links(client, body), moving_links(client, body)
        ignored = ignored_self_pairs(
            client, world.arm(arm.name).body, world.arm(arm.name).description.ignored_contacts
        )
        for i, a in enumerate(solid):
            for b in solid[i + 1 :]:
                if (min(a, b), max(a, b)) in ignored or not ({a, b} & moving):
                    continue
                names = (link_name(client, body, a), link_name(client, body, b))
                add(body, a, body, b, self_margin, names)
            if a in moving:
                for thing in others:
                    names = (link_name(client, body, a), thing.name)
                    add(body, a, thing.body_id, -1, clearance_m, names)
        for other_arm in arm_bodies[index + 1 :]:
            other = other_arm.body_id
            other_moving = moving_links(client, other)
            for a in solid:
                for b in solid_links(client, other):
                    if a in moving or b in other_moving:
                        names = (link_name(client, body, a), link_name(client, other, b))
                        add(body, a, other, b, clearance_m, names)
    return pairs


def measure(client: int, pairs: list[Pair], window_m: float) -> Measure:
    """PyBullet's distances of ``pairs`` at the bodies' current joint positions."""
    excess = window_m
    offending = []
    for pair in pairs:
        points = p.getClosestPoints(
            pair.body_a,
            pair.body_b,
            pair.margin + window_m,
            pair.link_a,
            pair.link_b,
            physicsClientId=client,
        )
        if not points:
            continue
        gap = min(point[8] for point in points) - pair.margin
        excess = min(excess, gap)
        if gap < -HULL_TOLERANCE_M:
            offending.append(pair.names)
    return Measure(excess, tuple(offending))


class ScratchCell:
    """The shared cell in a world of its own, its arms put anywhere without stepping."""

    def __init__(self, world: armfleet.World, clearance_m: float) -> None:
        self.world = world
        self.client = world.physics_client
        self.arms = [world.arm("bob"), world.arm("toby")]
        self.home = np.concatenate([arm.positions for arm in self.arms])
        self.pairs = counted_pairs(world, clearance_m)
        # The scene exactly as the planner builds it for a request of both arms (the
        # planner's snapshot and scenes are private: no public way leads to the checker).
        # This world never plans, so the scene lent here is nobody else's meanwhile.
        planner = world._planner
        with planner._scenes.scene(planner._snapshot(clearance_m)) as scene:
            self.checker: CollisionChecker = scene.checker(("bob", "toby"))

    def put(self, state: FloatArray) -> None:
        offset = 0
        for arm in self.arms:
            joints = pybullet_joints(self.client, arm)
            for joint, value in zip(joints, state[offset : offset + len(joints)], strict=True):
                p.resetJointState(
                    arm.body.body_id, joint, float(value), physicsClientId=self.client
                )
            offset += len(joints)

    def measure(self, state: FloatArray) -> Measure:
        self.put(state)
        return measure(self.client, self.pairs, 2 * BAND_M + HULL_TOLERANCE_M)

    def random_state(self, rng: np.random.Generator) -> FloatArray:
        parts = []
        for arm in self.arms:
            lower, upper = arm.joint_limits
            parts.append(rng.uniform(lower, upper))
        return np.concatenate(parts)

    def boundary_state(self, far: FloatArray, target_m: float) -> FloatArray | None:
        """A state on home -> ``far`` whose PyBullet excess is ``target_m`` (+-1 mm)."""
        near = self.home
        if self.measure(far).excess >= target_m:
            return None
        state = near
        for _ in range(BISECTION_STEPS):
            state = (near + far) / 2
            excess = self.measure(state).excess
            if abs(excess - target_m) < 1e-3:
                return state
            if excess > target_m:
                near = state
            else:
                far = state
        return None


@dataclass(frozen=True)
class Verdict:
    kind: str  # "uniform", "inside", "outside"
    measure: Measure
    valid: bool

    @property
    def pybullet_collides(self) -> bool:
        return self.measure.excess < -HULL_TOLERANCE_M

    @property
    def pybullet_clear(self) -> bool:
        return self.measure.excess > HULL_TOLERANCE_M

    @property
    def missed(self) -> bool:
        return self.pybullet_collides and self.valid

    @property
    def false_alarm(self) -> bool:
        return self.pybullet_clear and not self.valid

    @property
    def floor_only(self) -> bool:
        return all(FLOOR in names for names in self.measure.offending)


@pytest.fixture(scope="module", params=[0.01, 0.03], ids=["clearance 10 mm", "clearance 30 mm"])
def verdicts(request: pytest.FixtureRequest) -> Iterator[list[Verdict]]:
    clearance_m = float(request.param)
    world = armfleet.launch("shared_cell", viewer=False)
    try:
        cell = ScratchCell(world, clearance_m)
        rng = np.random.default_rng(16)
        found: list[Verdict] = []

        def judge(kind: str, state: FloatArray) -> None:
            found.append(Verdict(kind, cell.measure(state), cell.checker.valid(state)))

        for _ in range(UNIFORM_STATES):
            judge("uniform", cell.random_state(rng))
        for _ in range(BOUNDARY_LINES):
            far = cell.random_state(rng)
            for kind, target in (("inside", -BAND_M), ("outside", BAND_M)):
                state = cell.boundary_state(far, target)
                if state is not None:
                    judge(kind, state)
        yield found
    finally:
        world.close()


def summary(verdicts: list[Verdict]) -> str:
    decided = [v for v in verdicts if v.pybullet_collides or v.pybullet_clear]
    agree = [v for v in decided if not (v.missed or v.false_alarm)]
    kinds = {k: sum(v.kind == k for v in verdicts) for k in ("uniform", "inside", "outside")}
    misses = [v.measure.offending for v in verdicts if v.missed]
    rate = 100 * len(agree) / len(decided)
    return (
        f"{len(agree)}/{len(decided)} decided states agree ({rate:.1f} %), "
        f"{len(verdicts) - len(decided)} within the {HULL_TOLERANCE_M * 1000:g} mm band; "
        f"states {kinds}; misses {misses}; "
        f"false alarms {sum(v.false_alarm for v in verdicts)}"
    )


def test_the_scene_answers_as_pybullet_does(verdicts: list[Verdict]) -> None:
    """Arms against arms, objects and themselves: no state PyBullet sees closer than the
    margin passes, no state PyBullet sees clear is refused (floor: the next test)."""
    print(summary(verdicts))
    inside = [v for v in verdicts if v.kind == "inside" and v.pybullet_collides]
    outside = [v for v in verdicts if v.kind == "outside" and v.pybullet_clear]
    assert len(inside) >= 30 and len(outside) >= 30, summary(verdicts)
    assert not [v for v in verdicts if v.missed and not v.floor_only], summary(verdicts)
    assert not [v for v in verdicts if v.false_alarm], summary(verdicts)


def finger_floor_gap(world: armfleet.World, arm: armfleet.Arm, state: FloatArray) -> float:
    """PyBullet's distance [m] between ``arm``'s fingers at ``state`` and the floor."""
    client = world.physics_client
    floor = next(n.body_id for n in world.contacts.neighbours() if n.name == FLOOR)
    body = arm.body.body_id
    joints = pybullet_joints(client, arm)
    saved = [p.getJointState(body, j, physicsClientId=client)[0] for j in joints]
    for joint, value in zip(joints, state, strict=True):
        p.resetJointState(body, joint, float(value), physicsClientId=client)
    fingers = [arm.body.link_index(f"{arm.name}_panda_{side}finger") for side in ("left", "right")]
    gap = min(
        point[8]
        for link in fingers
        for point in p.getClosestPoints(body, floor, 0.1, link, -1, physicsClientId=client)
    )
    for joint, value in zip(joints, saved, strict=True):
        p.resetJointState(body, joint, value, physicsClientId=client)
    return float(gap)


def test_a_finger_within_the_clearance_of_the_floor_is_a_goal_in_collision() -> None:
    """bob's fingertips 6 mm over the floor (PyBullet's distance), tool pointing down:
    closer than the 10 mm clearance, so the goal is refused, naming a finger and the floor."""
    with armfleet.World() as world:
        bob = world.spawn("bob")
        pose = np.diag([1.0, -1.0, -1.0, 1.0])
        pose[:3, 3] = (0.5, 0.0, 0.0)
        low, high = 0.0, 0.05  # tcp heights [m]: fingers in the floor / well above it
        goal = bob.positions
        for _ in range(30):
            pose[2, 3] = (low + high) / 2
            goal = bob.solve_ik(pose, link="tcp")
            gap = finger_floor_gap(world, bob, goal)
            if abs(gap - 0.006) < 2e-4:
                break
            low, high = (pose[2, 3], high) if gap < 0.006 else (low, pose[2, 3])
        assert abs(finger_floor_gap(world, bob, goal) - 0.006) < 2e-4
        before = bob.positions
        with pytest.raises(PlanningFailed) as failure:
            bob.plan(goal, clearance_m=0.01)
        assert failure.value.reason is FailureReason.GOAL_IN_COLLISION
        assert FLOOR in failure.value.links and "finger" in " ".join(failure.value.links)
        world.run(0.1)
        assert np.abs(bob.positions - before).max() < 1e-4
