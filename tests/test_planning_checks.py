"""The compiled collision check and proof of clearance, against the Python check and PyBullet.

- The compiled check (``cpp/planning_check.cpp``) gives the Python reference's answer
  (Pinocchio's broadphase over the same pairs) on thousands of random states of two
  Pandas among objects, near and far, and the same first failure on whole paths.
- A segment the compiled certifier passes is clear in PyBullet at every 1e-3 rad.
- So is a curve the compiled curve proof passes (a motion that bows away from the chords
  between its knots, as a smooth timing's does), and curves that touch while their chords
  are clear are refused: the proof counts the deviation.
- The bound on a chord's deviation from its knots' accelerations holds for Ruckig's curves
  sampled every millisecond.
- At the smallest clearance allowed, no state the planner calls free touches anything in
  PyBullet (``performCollisionDetection`` + ``getContactPoints``, distance <= 0): the
  check accounts for Bullet's collision margin, on the shipped Panda and on an arm loaded
  from a file (example-robot-data's UR5).

PyBullet decides contact throughout; arms are put in place with ``resetJointState``
(no step). A contact counts when it involves a link some joint moves (a base standing on
the floor is not a contact of the plan).
"""

from __future__ import annotations

import sysconfig
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

import armfleet
from armfleet.checks.number_ranges import CLEARANCE_M
from armfleet.messages import FloatArray
from armfleet.planning.compiled_check import kernel_built
from armfleet.planning.curve_check import CurveCertifier
from armfleet.planning.path_check import PathCertifier
from armfleet.planning.path_timing import JointLimits
from armfleet.planning.scene import CollisionChecker
from armfleet.planning.smooth_timing import CurvedSegment

pytestmark = pytest.mark.skipif(not kernel_built(), reason="the compiled kernel is not built")

UR5_URDF = (
    Path(sysconfig.get_paths()["purelib"])
    / "cmeel.prefix/share/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
)
#: Random states compared between the compiled and the Python check.
AGREEMENT_STATES = 3000
#: Planner-free states checked in PyBullet per arm model (the issue's target).
FREE_STATES = 2000
#: Step of the dense re-check of a certified segment [rad, largest joint].
DENSE_STEP_RAD = 1e-3
#: Duration of the bowed test curves [s], and their knots (equal times apart).
CURVE_S, CURVE_KNOTS = 1.0, 2


@contextmanager
def planning_checker(
    world: armfleet.World, arms: Sequence[str], clearance_m: float, compiled: bool = True
) -> Iterator[CollisionChecker]:
    """The checker the planner builds for a request of ``arms`` (its scene is private:
    there is no public way to it)."""
    planner = world._planner
    with planner._scenes.scene(planner._snapshot(clearance_m)) as scene:
        yield scene.checker(tuple(arms), compiled=compiled)


def limits(world: armfleet.World, arms: Sequence[str]) -> tuple[FloatArray, FloatArray]:
    lower = np.concatenate([world.arm(a).position_controller.lower for a in arms])
    upper = np.concatenate([world.arm(a).position_controller.upper for a in arms])
    return lower, upper


class PyBulletContacts:
    """Puts arms in PyBullet and reports the contacts of their moving links."""

    def __init__(self, world: armfleet.World, arms: Sequence[str]) -> None:
        self.client = world.physics_client
        self.bodies = [world.arm(a).body.body_id for a in arms]
        self.joints: list[tuple[int, list[int]]] = []
        self.moving: dict[int, set[int]] = {}
        for name, body in zip(arms, self.bodies, strict=True):
            count = p.getNumJoints(body, physicsClientId=self.client)
            infos = [p.getJointInfo(body, j, physicsClientId=self.client) for j in range(count)]
            index = {info[1].decode(): j for j, info in enumerate(infos)}
            self.joints.append((body, [index[j] for j in world.arm(name).joint_names]))
            moves = {-1: False}
            for j, info in enumerate(infos):
                moves[j] = info[2] != p.JOINT_FIXED or moves[info[16]]
            self.moving[body] = {link for link, moved in moves.items() if moved}

    def put(self, state: FloatArray) -> None:
        offset = 0
        for body, joints in self.joints:
            for joint in joints:
                p.resetJointState(body, joint, float(state[offset]), physicsClientId=self.client)
                offset += 1

    def touching(self, state: FloatArray) -> list[tuple[int, int, int, int, float]]:
        """PyBullet's contacts (distance <= 0) of a moving link of the arms at ``state``."""
        self.put(state)
        p.performCollisionDetection(physicsClientId=self.client)
        found = []
        for body in self.bodies:
            for point in p.getContactPoints(bodyA=body, physicsClientId=self.client):
                a, b, link_a, link_b, distance = point[1], point[2], point[3], point[4], point[8]
                moved = link_a in self.moving.get(a, set()) or link_b in self.moving.get(b, set())
                if distance <= 0.0 and moved:
                    found.append((a, link_a, b, link_b, distance))
        return found


@pytest.fixture(scope="module")
def cell() -> Iterator[armfleet.World]:
    """Issue 16's cell: two Pandas over a table with a post, two walls and four cubes."""
    world = armfleet.launch("shared_cell", viewer=False)
    try:
        yield world
    finally:
        world.close()


def random_states(world: armfleet.World, arms: Sequence[str], count: int, seed: int) -> FloatArray:
    lower, upper = limits(world, arms)
    return np.random.default_rng(seed).uniform(lower, upper, (count, lower.size))


def test_the_compiled_check_answers_as_the_python_one(cell: armfleet.World) -> None:
    arms = ("bob", "toby")
    states = random_states(cell, arms, AGREEMENT_STATES, seed=1)
    with (
        planning_checker(cell, arms, 0.01) as fast,
        planning_checker(cell, arms, 0.01, compiled=False) as reference,
    ):
        assert fast.compiled is not None and reference.compiled is None
        near = [(fast.valid(s), reference.valid(s)) for s in states]
        far = [(fast.far(s), reference.far(s)) for s in states]
        assert all(a == b for a, b in near) and all(a == b for a, b in far)
        free_count = sum(a for a, _ in near)
        assert 0.2 * len(states) < free_count < 0.8 * len(states)  # both answers seen
        assert fast.checks == 2 * len(states)
        free = states[[a for a, _ in near]]
        PathCertifier(fast)  # hands the compiled check the proof's numbers
        reference_proof = PathCertifier(reference)
        outcomes = set()
        for k in range(40):
            path = np.array([free[k], free[k] + 0.5 * (free[k + 1] - free[k]), free[k + 1]])
            # The compiled walk of path_check.py, step for step (adaptive=False).
            ours = fast.compiled.first_failure(path, adaptive=False)
            theirs = reference_proof.first_failure(path)
            assert (ours is None) == (theirs is None)
            if ours is not None and theirs is not None:
                assert ours[0] == theirs[0]
                np.testing.assert_allclose(ours[1], theirs[1], rtol=0.0, atol=1e-12)
            outcomes.add(ours is None)
        assert outcomes == {True, False}  # paths proven clear and paths refused


def test_a_segment_the_compiled_certifier_passes_is_clear_in_pybullet(
    cell: armfleet.World,
) -> None:
    arms = ("bob", "toby")
    clearance = CLEARANCE_M.low
    contacts = PyBulletContacts(cell, arms)
    generator = np.random.default_rng(2)
    passed, rechecked = 0, 0
    try:
        with planning_checker(cell, arms, clearance) as checker:
            certifier = PathCertifier(checker)
            for start in random_states(cell, arms, 400, seed=3):
                if passed == 8:
                    break
                if not checker.valid(start):
                    continue
                direction = generator.normal(size=start.size)
                end = start + 0.25 * direction / np.abs(direction).max()
                if certifier.first_failure(np.array([start, end])) is not None:
                    continue
                passed += 1
                count = int(np.ceil(np.abs(end - start).max() / DENSE_STEP_RAD))
                for s in np.linspace(0.0, 1.0, count + 1):
                    rechecked += 1
                    assert contacts.touching(start + s * (end - start)) == []
    finally:
        contacts.put(np.concatenate([cell.arm(a).positions for a in arms]))
    assert passed == 8 and rechecked > 8 * 250


@pytest.mark.parametrize("model", ["panda", str(UR5_URDF)], ids=["panda", "ur5 from a file"])
def test_at_the_smallest_clearance_no_free_state_touches_in_pybullet(model: str) -> None:
    with armfleet.World() as world:
        world.spawn("arm", model=model)
        # Something to hit besides the floor and the arm itself, within its reach.
        world.add_object("block", "box", size=(0.25, 0.25, 0.3), at=(0.0, 0.5, 0.15), mass=0.0)
        world.add_object("pole", "cylinder", size=(0.04, 0.8), at=(-0.45, -0.3, 0.4), mass=0.0)
        contacts = PyBulletContacts(world, ["arm"])
        free, touching = 0, []
        with planning_checker(world, ["arm"], CLEARANCE_M.low) as checker:
            for state in random_states(world, ["arm"], 6 * FREE_STATES, seed=4):
                if free == FREE_STATES:
                    break
                if not checker.valid(state):
                    continue
                free += 1
                found = contacts.touching(state)
                if found:
                    touching.append((state, found))
        assert free == FREE_STATES
        assert touching == []


def bowed(start: FloatArray, end: FloatArray, bow: FloatArray, times: FloatArray) -> FloatArray:
    """A curve from ``start`` to ``end`` in :data:`CURVE_S` that bows out by ``bow`` mid-way
    (per joint ``4 bow u (1 - u)`` off the straight line, ``u = t / CURVE_S``): its
    acceleration is ``8 |bow| / CURVE_S^2``, constant."""
    u = (times / CURVE_S)[:, None]
    return start + u * (end - start) + 4.0 * bow * u * (1.0 - u)


def test_curves_the_compiled_proof_passes_are_clear_and_bows_into_things_are_refused(
    cell: armfleet.World,
) -> None:
    """Curves of one chord each, bowing off it by up to a few tenths of a radian: the proof
    must count the deviation, or curves that touch pass on their chord's proof."""
    arms = ("bob", "toby")
    contacts = PyBulletContacts(cell, arms)
    generator = np.random.default_rng(5)
    knot_times = np.linspace(0.0, CURVE_S, CURVE_KNOTS)
    passed, bowed_into_something, rechecked = 0, 0, 0
    try:
        with planning_checker(cell, arms, CLEARANCE_M.low) as checker:
            chords = PathCertifier(checker)
            for index, start in enumerate(random_states(cell, arms, 1500, seed=6)):
                if passed >= 6 and bowed_into_something >= 2:
                    break
                if not checker.valid(start):
                    continue
                direction = generator.normal(size=start.size)
                end = start + 0.3 * direction / np.abs(direction).max()
                bow = generator.normal(size=start.size) * (0.02 if index % 2 else 0.1)
                knots = bowed(start, end, bow, knot_times)
                curve = CurveCertifier(checker, 8.0 * np.abs(bow) / CURVE_S**2 + 1e-12)
                verdict = curve.first_failure(knots, CURVE_S / (CURVE_KNOTS - 1))
                count = int(np.ceil(np.abs(end - start).max() / DENSE_STEP_RAD))
                dense = bowed(start, end, bow, np.linspace(0.0, CURVE_S, count + 1))
                if verdict is None:
                    passed += 1
                    for state in dense:
                        rechecked += 1
                        assert contacts.touching(state) == []
                elif chords.first_failure(knots) is None and any(
                    contacts.touching(state) for state in dense[::4]
                ):
                    bowed_into_something += 1  # its chords are clear, the curve is not
    finally:
        contacts.put(np.concatenate([cell.arm(a).positions for a in arms]))
    assert passed >= 6 and bowed_into_something >= 2 and rechecked > 6 * 250


def test_a_chords_deviation_bound_holds_for_ruckigs_motions(cell: armfleet.World) -> None:
    """The bound from the knots' accelerations and the jerk limit, against Ruckig's curves
    sampled every millisecond: no joint strays further from a chord than its bound."""
    arms = ("bob", "toby")
    limits = JointLimits(np.full(14, 2.0), np.full(14, 5.0), np.full(14, 50.0))
    generator = np.random.default_rng(7)
    tight = 0
    with planning_checker(cell, arms, 0.01) as checker:
        certifier = CurveCertifier(checker, limits.acceleration, limits.jerk)
        for _ in range(20):
            start, end = generator.uniform(-1.0, 1.0, (2, 14))
            speeds = generator.uniform(-1.0, 1.0, (2, 14)) * (np.sign(end - start) != 0)
            try:
                segment = CurvedSegment(start, end, speeds[0], speeds[1], limits)
            except ValueError:
                continue
            count = max(1, int(np.ceil(segment.duration / certifier.knot_period)))
            times = np.linspace(0.0, segment.duration, count + 1)
            knots, _, accelerations = segment.at(times)
            bounds = certifier.chord_deviations(segment.duration / count, accelerations)
            worst = certifier.chord_deviations(segment.duration / count, None)[0]
            for k in range(count):
                dense = np.linspace(times[k], times[k + 1], 60)
                states = segment.at(dense)[0]
                u = ((dense - times[k]) / (times[k + 1] - times[k]))[:, None]
                chord = knots[k] + u * (knots[k + 1] - knots[k])
                strayed = np.abs(states - chord).max(axis=0)
                assert np.all(strayed <= bounds[k] + 1e-12)
                assert np.all(bounds[k] <= worst + 1e-15)
                tight += int(np.any(bounds[k] < 0.5 * worst))
    assert tight > 0  # the knots' accelerations do tighten the bound somewhere
