"""Safety: contacts are reported, touching arms stop and hold, faults stay in their arm."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

import armfleet
from armfleet.errors import ArmFault, ProtectiveStopError, SelfContactError
from armfleet.messages import ArmMode, ArmStatus, CollisionReport, JointCommand, JointState

MAX_INTERPENETRATION_M = 5e-3
NORMAL_TRACKING_BOUND_RAD = 1e-3


def lean_forward(arm: armfleet.Arm) -> np.ndarray:
    target = arm.positions.copy()
    target[1] += 1.0  # shoulder forward
    target[3] += 1.2  # elbow open
    return target


@pytest.fixture
def facing() -> Iterator[armfleet.World]:
    """bob at (0, 0) and toby at (0.8, 0) facing him: close enough to touch."""
    with armfleet.World() as world:
        world.spawn("bob", at=(0, 0))
        world.spawn("toby", at=(0.8, 0, 0, 180))
        yield world


def test_touching_arms_stop_hold_and_move_apart_after_reset(facing: armfleet.World) -> None:
    bob, toby = facing.arm("bob"), facing.arm("toby")
    reports: list[CollisionReport] = []
    statuses: list[ArmStatus] = []
    facing.bus.subscribe("/collisions", reports.append)
    facing.bus.subscribe("/bob/status", statuses.append)
    bob.move_to(lean_forward(bob))
    toby.move_to(lean_forward(toby))
    facing.run(2.5)

    contacts = [c for r in reports for c in r.contacts]
    assert contacts, "the arms must have touched"
    first = contacts[0]
    assert {first.body_a, first.body_b} == {"bob", "toby"}
    assert first.link_a.startswith(first.body_a + "_") and first.link_b.startswith(first.body_b)
    assert 0.2 < first.position[0] < 0.6  # between the two bases
    deepest = max(c.depth for c in contacts)
    print(f"deepest interpenetration {deepest * 1e3:.3f} mm")
    assert deepest < MAX_INTERPENETRATION_M

    for arm, other in ((bob, "toby"), (toby, "bob")):
        status = arm.status(facing.time)
        assert status.mode is ArmMode.PROTECTIVE_STOP
        assert f"touched {other}" in status.reason
        assert not arm.is_moving
    assert any(s.mode is ArmMode.PROTECTIVE_STOP for s in statuses)
    held = bob.positions
    facing.run(0.5)
    assert np.abs(bob.positions - held).max() < 1e-3  # holds where it stopped

    home = np.array(bob.description.home)
    with pytest.raises(ProtectiveStopError, match="reset_stop"):
        bob.move_to(home)
    bob.reset_stop()
    toby.reset_stop()
    bob.move_to(home)
    toby.move_to(home)
    facing.run(3.0)
    for arm in (bob, toby):
        assert arm.status(facing.time).mode is ArmMode.HOLDING
        assert np.abs(arm.positions - home).max() < 1e-4
    assert facing.contacts.touching_bodies("bob") == set()


def test_protective_stop_is_configurable_per_arm() -> None:
    with armfleet.World() as world:
        bob = world.spawn("bob", parameters={"position_controller": {"protective_stop": False}})
        toby = world.spawn("toby", at=(0.8, 0, 0, 180))
        bob.move_to(lean_forward(bob))
        toby.move_to(lean_forward(toby))
        world.run(2.5)
        assert world.contacts.total_contacts > 0
        assert toby.status(world.time).mode is ArmMode.PROTECTIVE_STOP
        assert bob.status(world.time).mode is not ArmMode.PROTECTIVE_STOP


def test_contact_with_the_floor_stops_the_arm() -> None:
    with armfleet.World() as world:
        arm = world.spawn("bob", model="ur5")
        target = arm.positions.copy()
        # Swing the upright arm down through the floor (not so far that the target folds
        # the upper arm into the base: a move refuses that, see test_self_touching_targets).
        target[1] += 1.8
        arm.move_to(target)
        world.run(3.0)
        status = arm.status(world.time)
        assert status.mode is ArmMode.PROTECTIVE_STOP
        assert "touched ground" in status.reason
        assert np.abs(arm.positions - target).max() > 0.1  # it did not go through


def test_folding_the_wrist_into_the_forearm_stops_the_arm() -> None:
    """A Panda's wrist (link7) driven into its forearm (link5) by the wrist joint alone.

    The upstream SRDF disables link5-link7, so before the sampled contact pairs
    (armfleet/physics/contact_pairs.py) this self-contact raised no stop and the
    wrist pushed 9 mm into the forearm at the joint's limit. A move refuses this target
    (SelfContactError, see test_self_touching_targets.py); sent on the raw command topic,
    which only checks limits, it shows the physics' stop."""
    with armfleet.World() as world:
        arm = world.spawn("bob")
        contacts: list[CollisionReport] = []
        world.bus.subscribe("/collisions", contacts.append)
        target = arm.positions.copy()
        target[5] = arm.joint_limits[0][5] + 0.01  # joint 6 to its lower limit: folded
        with pytest.raises(SelfContactError, match="bob_panda_link5 / bob_panda_link7"):
            arm.move_to(target)
        world.bus.publish("/bob/position_controller/commands", JointCommand(tuple(target)))
        world.run(3.0)
        status = arm.status(world.time)
        assert status.mode is ArmMode.PROTECTIVE_STOP
        assert "bob_panda_link5" in status.reason and "bob_panda_link7" in status.reason
        assert np.abs(arm.positions - target).max() > 0.05  # it stopped on the way
        deepest = max(c.depth for report in contacts for c in report.contacts)
        assert deepest < MAX_INTERPENETRATION_M


def test_a_new_contact_after_reset_stops_again(facing: armfleet.World) -> None:
    bob, toby = facing.arm("bob"), facing.arm("toby")
    bob.move_to(lean_forward(bob))
    toby.move_to(lean_forward(toby))
    facing.run(2.5)
    assert bob.status(facing.time).mode is ArmMode.PROTECTIVE_STOP
    bob.reset_stop()
    bob.move_to(np.array(bob.description.home))
    facing.run(2.0)  # bob leaves; toby stays stopped where it was
    assert facing.contacts.touching_bodies("bob") == set()
    bob.move_to(lean_forward(bob))  # and comes back: a new contact
    facing.run(2.5)
    assert bob.status(facing.time).mode is ArmMode.PROTECTIVE_STOP


@pytest.mark.parametrize("fault", ["raises", "nan"])
def test_a_faulty_controller_puts_only_its_arm_in_error(pair: armfleet.World, fault: str) -> None:
    bob, toby = pair.arm("bob"), pair.arm("toby")
    tracking: list[float] = []
    pair.bus.subscribe(
        "/toby/position_controller/state",
        lambda s: tracking.append(float(np.abs(s.reference_position - s.position).max())),
    )
    bob_states: list[JointState] = []
    pair.bus.subscribe("/bob/joint_states", bob_states.append)
    toby.move_to(toby.positions + 0.5)  # clear of itself with the gripper half open
    pair.run(0.2)
    if fault == "raises":

        def broken(*args: object) -> None:
            raise RuntimeError("solver diverged")

        # The reference step (Ruckig) runs in Python on both the compiled and the numpy
        # path of the position controller: it stands in for any step that raises.
        bob.position_controller.advance = broken  # type: ignore[method-assign,assignment]
    else:
        bob.position_controller._kp[:] = float("nan")
    bob.move_to(bob.positions + 0.2)
    pair.run(0.1)

    status = bob.status(pair.time)
    assert status.mode is ArmMode.ERROR
    assert ("solver diverged" if fault == "raises" else "non-finite torques") in status.reason
    assert toby.status(pair.time).mode is ArmMode.MOVING
    held = bob.positions
    count = len(bob_states)
    pair.run(1.5)
    assert len(bob_states) > count + 1000  # the broadcaster still reports
    assert np.abs(bob.positions - held).max() < 2e-3  # the brakes hold it
    assert max(tracking) < NORMAL_TRACKING_BOUND_RAD  # toby never noticed
    assert np.abs(toby.positions - (toby.joint_state.position[:7])).max() < 1e-2
    with pytest.raises(ArmFault, match="reset"):
        bob.move_to(bob.positions)

    if fault == "raises":
        del bob.position_controller.advance  # the class's own again
    else:
        bob.position_controller._kp[:] = bob.position_controller.parameters["kp_s2"]
    bob.reset()
    assert bob.status(pair.time).mode is ArmMode.HOLDING
    target = np.array(bob.description.home)
    bob.move_to(target)
    pair.run(2.0)
    assert np.abs(bob.positions - target).max() < 1e-4


def test_velocity_never_exceeds_urdf_limits_over_random_targets() -> None:
    """60 s of random reachable targets, a third sent mid-motion: |v| <= 1.01 x limit."""
    rng = np.random.default_rng(11)
    with armfleet.World() as world:
        # On a pedestal (no floor in reach); self-contacts may happen and must not stop it.
        no_stop = {"position_controller": {"protective_stop": False}}
        arm = world.spawn("bob", at=(0, 0, 1.0), parameters=no_stop)
        limits = arm.kinematics.velocity_limit
        worst = np.zeros_like(limits)

        def track(state: JointState) -> None:
            np.maximum(worst, np.abs(state.velocity) / limits, out=worst)

        world.bus.subscribe("/bob/joint_states", track)
        lower, upper = arm.joint_limits
        for _ in range(60):
            target = lower + (upper - lower) * rng.uniform(0.15, 0.85, lower.size)
            try:
                arm.move_to(target)
            except armfleet.ArmfleetError:
                continue  # a re-plan that would overshoot a limit is refused: fine
            world.run(rng.uniform(0.3, 1.5))
        print(f"worst velocity / URDF limit: {worst.max():.4f}")
        assert worst.max() <= 1.01
        assert worst.max() > 0.9  # the limit was actually approached


def test_torque_saturation_is_counted_per_joint() -> None:
    with armfleet.World() as world:
        aggressive = {"max_acceleration_rad_s2": 400.0, "max_jerk_rad_s3": 1e5}
        bob = world.spawn("bob", parameters={"position_controller": aggressive})
        calm = world.spawn("calm", at=(1, 0))
        statuses: list[ArmStatus] = []
        world.bus.subscribe("/bob/status", statuses.append)
        for arm in (bob, calm):
            arm.move_to(arm.positions + 0.8)
        world.run(2.0)
        assert sum(bob.status(world.time).saturation_steps) > 0
        assert sum(calm.status(world.time).saturation_steps) == 0
        assert statuses[-1].saturation_steps == bob.status(statuses[-1].stamp).saturation_steps


def test_short_soak_runs_clean(tmp_path) -> None:
    """The soak script's CI mode: 4 neighbouring arms, random targets, contacts on."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "benchmarks" / "soak.py"
    out = tmp_path / "soak.json"
    result = subprocess.run(
        [sys.executable, str(script), "--short", "--json", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stdout + result.stderr
    figures = json.loads(out.read_text())
    assert figures["non_finite_states"] == 0
    assert figures["all_tracking"] is True
    assert figures["rss_growth_pct"] < 5.0
    assert figures["simulated_s"] >= 10.0
