"""Fleet benchmark: armfleet's full stack against the plain PyBullet a user would write.

For N Pandas on a 1 m grid at a 1 ms step it measures, per physics step:
  (a) bare   - PyBullet's stepSimulation alone, armfleet's bodies limp (torque mode);
  (b) motors - PyBullet's built-in POSITION_CONTROL on armfleet's bodies;
  (c) stack  - armfleet's full step: broadcasters, Ruckig, Pinocchio, torque writes,
               grippers, contacts and protective stops, every arm following random
               reachable targets;
  (d) plain  - the peer (benchmarks/plain_pybullet.py): the upstream Panda with default
               loadURDF flags, per arm a Ruckig step and POSITION_CONTROL with position
               and velocity feed-forward, fed the same kind of targets;
  (e) plain limp - the peer's bodies limp (the physics alone).
All take turns, repeat by repeat, so a drift in the machine's speed hits them alike. It
prints medians (min-max over repeats), the ratios c/d (the target: <= 1.0 at 30 arms,
<= 1.5 at 1 and 2) and c/a, the real-time factor, the bring-up time of 30 arms, peak
RSS with 30 arms, and the tracking error of armfleet vs the built-in motors on the same
Ruckig trajectory; and writes benchmarks/results/fleet.json.

    python benchmarks/fleet.py            # N = 1, 2, 10, 30 (a few minutes)
    python benchmarks/fleet.py --short    # N = 2, a few hundred steps (CI)
"""

from __future__ import annotations

# ruff: noqa: I001 - armfleet comes first: it imports PyBullet without its banner
import armfleet

import argparse
import contextlib
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pybullet as p

from armfleet.controllers.jerk_limited_trajectory import JerkLimitedTrajectory
from plain_pybullet import PlainFleet  # benchmarks/ is the script's folder

RESULTS = Path(__file__).resolve().parent / "results"
GRID_COLUMNS = 6


def grid_world(arms: int) -> armfleet.World:
    world = armfleet.World()
    for i in range(arms):
        world.spawn(f"arm{i}", at=(float(i // GRID_COLUMNS), float(i % GRID_COLUMNS)))
    return world


def random_targets(world: armfleet.World, rng: np.random.Generator) -> None:
    for arm in world.arms.values():
        if not arm.is_moving:
            lower, upper = arm.joint_limits
            home = np.array(arm.description.home)
            # Within reach of home, so neighbours 1 m apart rarely touch.
            target = np.clip(home + rng.uniform(-0.4, 0.4, home.size), lower + 0.05, upper - 0.05)
            with contextlib.suppress(armfleet.ArmfleetError):  # a refused re-plan: next time
                arm.move_to(target)


def timed(
    repeats: int, steps: int, prepare: Callable[[], None], step: Callable[[], None]
) -> list[float]:
    """Microseconds per step for each repeat."""
    samples = []
    for _ in range(repeats):
        prepare()
        started = time.perf_counter()
        for _ in range(steps):
            step()
        samples.append((time.perf_counter() - started) / steps * 1e6)
    return samples


def measure(arms: int, repeats: int, steps: int, seed: int) -> dict[str, object]:
    world = grid_world(arms)
    client = world.physics_client
    bodies = [(arm.body.body_id, arm.body.joint_indices) for arm in world.arms.values()]
    snapshot = p.saveState(physicsClientId=client)

    def restore() -> None:
        p.restoreState(snapshot, physicsClientId=client)

    def bare_prepare() -> None:
        restore()
        for body, joints in bodies:  # torque mode, motors off, as the stack runs
            p.setJointMotorControlArray(
                body, joints, p.VELOCITY_CONTROL, forces=[0.0] * len(joints), physicsClientId=client
            )

    targets = {body: [0.0] * len(joints) for body, joints in bodies}

    def motors_prepare() -> None:
        restore()
        for body, joints in bodies:
            states = p.getJointStates(body, joints, physicsClientId=client)
            targets[body] = [s[0] for s in states]

    def motors_step() -> None:
        for body, joints in bodies:
            p.setJointMotorControlArray(
                body, joints, p.POSITION_CONTROL, targetPositions=targets[body],
                physicsClientId=client,
            )  # fmt: skip
        p.stepSimulation(physicsClientId=client)

    for arm in world.arms.values():  # the stack: torque mode, holding
        arm.body.release_brakes()
    world.run(0.05)
    rng = np.random.default_rng(seed)
    peer = PlainFleet(arms, GRID_COLUMNS)
    peer_rng = np.random.default_rng(seed)
    for _ in range(50):
        peer.step()
    bare: list[float] = []
    motors: list[float] = []
    stack: list[float] = []
    plain: list[float] = []
    plain_errors: list[float] = []
    plain_limp: list[float] = []
    # Interleaved (a, b, c, a, b, c, ...): the three see the same machine, whose speed
    # drifts over minutes. The stack resumes from where it left off each time.
    for _ in range(repeats):
        paused = p.saveState(physicsClientId=client)
        bare += timed(1, steps, bare_prepare, lambda: p.stepSimulation(physicsClientId=client))
        motors += timed(1, steps, motors_prepare, motors_step)
        p.restoreState(paused, physicsClientId=client)
        p.removeState(paused, physicsClientId=client)
        for arm in world.arms.values():  # PyBullet's motors off again
            arm.body.release_brakes()
        stack += timed(1, steps, lambda: random_targets(world, rng), world.step)
        plain += timed(1, steps, lambda: peer.random_targets(peer_rng), peer.step)
        plain_errors.append(peer.tracking_error())
        paused = p.saveState(physicsClientId=peer.client)
        plain_limp += timed(
            1, steps, peer.go_limp, lambda: p.stepSimulation(physicsClientId=peer.client)
        )
        p.restoreState(paused, physicsClientId=peer.client)
        p.removeState(paused, physicsClientId=peer.client)
    world.close()
    peer.close()
    a, b, c, d = (statistics.median(x) for x in (bare, motors, stack, plain))
    return {
        "arms": arms,
        "bare_us": summary(bare),
        "motors_us": summary(motors),
        "stack_us": summary(stack),
        "plain_us": summary(plain),
        "plain_limp_us": summary(plain_limp),
        "stack_over_plain": round(c / d, 3),
        "stack_over_bare": round(c / a, 3),
        "stack_over_motors": round(c / b, 3),
        "realtime_factor": round(1e3 / c, 3),
        "plain_realtime_factor": round(1e3 / d, 3),
        "plain_targets": peer.targets_given,
        "plain_tracking_error_rad": max(plain_errors),
    }


def summary(samples: list[float]) -> dict[str, float]:
    return {
        "median": round(statistics.median(samples), 1),
        "min": round(min(samples), 1),
        "max": round(max(samples), 1),
    }


def bringup_and_rss(arms: int) -> dict[str, float]:
    """Bring-up time and peak RSS of a fresh process holding ``arms`` Pandas."""
    code = (
        "import time, armfleet\n"
        "from armfleet.spec import load_spec, FleetSpec\n"
        f"spec = load_spec('grid_30'); spec = FleetSpec(spec.world, spec.arms[:{arms}])\n"
        "t = time.perf_counter(); w = armfleet.launch(spec, viewer=False)\n"
        "up = time.perf_counter() - t; w.run(0.5)\n"
        # VmHWM, not ru_maxrss: Linux carries ru_maxrss over from the parent at fork.
        "hwm = [l for l in open('/proc/self/status') if l.startswith('VmHWM')][0]\n"
        "print(up, int(hwm.split()[1]) / 1024)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=600
    ).stdout.split()
    return {
        "arms": arms,
        "bringup_s": round(float(out[0]), 3),
        "peak_rss_mb": round(float(out[1]), 1),
    }


def tracking_comparison() -> dict[str, float]:
    """Max tracking error on one Ruckig trajectory: armfleet vs PyBullet's position motors.

    The motors are given the reference position each step with the URDF effort limits,
    as they are usually driven ("position only"), and also with the reference velocity
    as feed-forward ("position + velocity"), which PyBullet's motor constraint tracks
    much better.
    """
    with armfleet.World() as world:
        arm = world.spawn("bob")
        target = arm.positions + np.array([0.8, 0.6, -0.7, 0.8, 0.9, -0.8, 0.9])
        errors: list[float] = []
        world.bus.subscribe(
            "/bob/position_controller/state",
            lambda s: errors.append(float(np.abs(s.reference_position - s.position).max())),
        )
        start = arm.positions
        arm.move_to(target)
        while arm.is_moving:
            world.step()
        ours = max(errors)
        limits = arm.position_controller
        velocity = limits.max_velocity
        acceleration = np.full(7, float(limits.parameters["max_acceleration_rad_s2"]))
        jerk = np.full(7, float(limits.parameters["max_jerk_rad_s3"]))
    theirs = {}
    for variant, feed_forward in (("position_only", False), ("position_and_velocity", True)):
        reference = JerkLimitedTrajectory(start, 0.001, velocity, acceleration, jerk)
        theirs[variant] = motors_tracking(reference, target, feed_forward)
    return {
        "armfleet_max_error_rad": ours,
        "position_control_max_error_rad": theirs["position_only"],
        "position_control_with_velocity_max_error_rad": theirs["position_and_velocity"],
        "improvement": round(theirs["position_only"] / ours, 1),
        "improvement_with_velocity": round(theirs["position_and_velocity"] / ours, 2),
    }


def motors_tracking(
    reference: JerkLimitedTrajectory, target: np.ndarray, feed_forward: bool
) -> float:
    """Max error of PyBullet's POSITION_CONTROL following ``reference`` to ``target``."""
    with armfleet.World() as world:
        arm = world.spawn("bob")
        client, body = world.physics_client, arm.body
        arm.controller_manager.shutdown()  # PyBullet's motors take over
        reference.follow(reference.plan(target))
        arm_joints = [body.joint_indices[i] for i in arm.kinematics.arm_indices]
        effort = arm.kinematics.effort_limit[arm.kinematics.arm_indices].tolist()
        worst = 0.0
        while reference.moving:
            extra = {"targetVelocities": reference.velocity.tolist()} if feed_forward else {}
            p.setJointMotorControlArray(
                body.body_id, arm_joints, p.POSITION_CONTROL,
                targetPositions=reference.position.tolist(), forces=effort,
                physicsClientId=client, **extra,
            )  # fmt: skip
            p.stepSimulation(physicsClientId=client)
            reference.advance()
            states = p.getJointStates(body.body_id, arm_joints, physicsClientId=client)
            measured = np.array([s[0] for s in states])
            worst = max(worst, float(np.abs(reference.position - measured).max()))
        return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="N = 2, few steps (CI)")
    parser.add_argument("--json", type=Path, default=RESULTS / "fleet.json")
    args = parser.parse_args()
    sizes, repeats, steps = ((2,), 3, 100) if args.short else ((1, 2, 10, 30), 7, 300)
    load = os.getloadavg()[0]
    rows = [measure(n, repeats, steps, seed=n) for n in sizes]
    fleet = bringup_and_rss(2 if args.short else 30)
    tracking = tracking_comparison()
    print(f"machine load (1 min) before: {load:.2f}, after: {os.getloadavg()[0]:.2f}")
    columns = ("bare_us", "motors_us", "stack_us", "plain_us", "plain_limp_us")
    headers = ("(a) bare us", "(b) motors us", "(c) stack us", "(d) plain us", "(e) plain limp")
    print(f"{'arms':>4} " + " ".join(f"{h:>16}" for h in headers)
          + f" {'c/d':>6} {'c/a':>6} {'RTF':>6}")  # fmt: skip
    for row in rows:
        cells = [fmt(row[key]) for key in columns]  # type: ignore[arg-type]
        print(f"{row['arms']:>4} " + " ".join(f"{cell:>16}" for cell in cells)
              + f" {row['stack_over_plain']:>6} {row['stack_over_bare']:>6}"
              f" {row['realtime_factor']:>6}")  # fmt: skip
    print(f"bring-up of {fleet['arms']} arms: {fleet['bringup_s']} s, "
          f"peak RSS {fleet['peak_rss_mb']} MB")  # fmt: skip
    print(f"tracking on one Ruckig move: armfleet {tracking['armfleet_max_error_rad']:.2e} rad; "
          f"POSITION_CONTROL {tracking['position_control_max_error_rad']:.2e} rad "
          f"({tracking['improvement']}x ours), with velocity feed-forward "
          f"{tracking['position_control_with_velocity_max_error_rad']:.2e} rad "
          f"({tracking['improvement_with_velocity']}x ours)")  # fmt: skip
    result = {
        "load_before": load, "load_after": os.getloadavg()[0], "steps": steps,
        "repeats": repeats, "sizes": rows, "fleet": fleet, "tracking": tracking,
        "peak_rss_this_process_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }  # fmt: skip
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2))


def fmt(cell: dict[str, float]) -> str:
    return f"{cell['median']:.0f} ({cell['min']:.0f}-{cell['max']:.0f})"


if __name__ == "__main__":
    main()
