"""Timed waypoints sampled as joint_trajectory_controller interpolates them
(armfleet/motion/timed_trajectory.py), against SciPy's splines: a cubic Hermite through
positions and velocities, and a quintic matching positions, velocities and accelerations
at both ends of every segment; positions alone give a smooth curve through every point
at its time; and every bad input is one line naming the problem."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BPoly, CubicHermiteSpline

from armfleet.motion.timed_trajectory import TrajectoryRefused, check_waypoints, sample_waypoints

PERIOD = 0.001
JOINTS = 3


def _start(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return rng.normal(size=JOINTS), rng.normal(size=JOINTS) * 0.1, rng.normal(size=JOINTS) * 0.1


@pytest.mark.parametrize("seed", range(4))
def test_positions_and_velocities_follow_scipys_cubic_hermite(seed: int) -> None:
    rng = np.random.default_rng(seed)
    start = _start(rng)
    times = np.cumsum(rng.uniform(0.2, 0.6, size=4))
    positions = rng.normal(size=(4, JOINTS))
    velocities = rng.normal(size=(4, JOINTS)) * 0.3
    velocities[-1] = 0.0
    waypoints = check_waypoints("bob", JOINTS, times, positions, velocities)
    motion = sample_waypoints(waypoints, start, PERIOD)
    knots = np.concatenate([[0.0], times])
    spline = CubicHermiteSpline(
        knots, np.vstack([start[0], positions]), np.vstack([start[1], velocities])
    )
    t = np.arange(1, motion.steps + 1) * PERIOD
    t[-1] = times[-1]
    np.testing.assert_allclose(motion.position, spline(t), atol=1e-9)
    np.testing.assert_allclose(motion.velocity[:-1], spline(t[:-1], 1), atol=1e-9)
    np.testing.assert_allclose(motion.acceleration[:-1], spline(t[:-1], 2), atol=1e-7)


@pytest.mark.parametrize("seed", range(4))
def test_with_accelerations_each_segment_is_scipys_quintic(seed: int) -> None:
    rng = np.random.default_rng(10 + seed)
    start = _start(rng)
    times = np.cumsum(rng.uniform(0.2, 0.6, size=3))
    positions = rng.normal(size=(3, JOINTS))
    velocities = rng.normal(size=(3, JOINTS)) * 0.3
    accelerations = rng.normal(size=(3, JOINTS)) * 0.3
    velocities[-1] = accelerations[-1] = 0.0
    waypoints = check_waypoints("bob", JOINTS, times, positions, velocities, accelerations)
    motion = sample_waypoints(waypoints, start, PERIOD)
    knots = np.concatenate([[0.0], times])
    values = np.stack(
        [
            np.vstack([start[0], positions]),
            np.vstack([start[1], velocities]),
            np.vstack([start[2], accelerations]),
        ],
        axis=1,
    )  # (knots, derivatives, joints)
    spline = BPoly.from_derivatives(knots, values)
    t = np.arange(1, motion.steps + 1) * PERIOD
    t[-1] = times[-1]
    np.testing.assert_allclose(motion.position, spline(t), atol=1e-9)
    np.testing.assert_allclose(motion.velocity[:-1], spline(t[:-1], 1), atol=1e-8)
    np.testing.assert_allclose(motion.acceleration[:-1], spline(t[:-1], 2), atol=1e-6)


def test_positions_alone_pass_every_point_at_its_time_smoothly() -> None:
    start = (np.zeros(JOINTS), np.zeros(JOINTS), np.zeros(JOINTS))
    times = np.array([0.5, 1.0, 1.7, 2.0])
    positions = np.array([[0.2, -0.1, 0.0], [0.5, -0.3, 0.1], [0.4, -0.2, 0.3], [0.1, 0.0, 0.3]])
    motion = sample_waypoints(check_waypoints("bob", JOINTS, times, positions), start, PERIOD)
    for time, point in zip(times, positions, strict=True):
        np.testing.assert_allclose(motion.position[round(time / PERIOD) - 1], point, atol=1e-12)
    # Continuous velocity (no jump at the waypoints), at rest at the end.
    jumps = np.abs(np.diff(motion.velocity, axis=0)).max()
    assert jumps < 0.02  # per 1 ms: accelerations stay finite
    assert np.all(motion.velocity[-1] == 0.0)


@pytest.mark.parametrize(
    ("times", "positions", "velocities", "word"),
    [
        ([], [], None, "no points"),
        ([1.0], [[0.0, 0.0]], None, "expected 3"),
        ([0.0], [[0.0] * 3], None, "> 0"),
        ([1.0, 1.0], [[0.0] * 3] * 2, None, "increase"),
        ([1.0], [[float("nan"), 0.0, 0.0]], None, "finite"),
        ([1.0], [[0.0] * 3], [[1.0, 0.0, 0.0]], "rest"),
        ([1.0], [[0.0] * 3], [[0.0] * 2], "velocities"),
        ([1e9], [[0.0] * 3], None, "at most"),
    ],
)
def test_bad_waypoints_are_one_line(times, positions, velocities, word) -> None:
    with pytest.raises(TrajectoryRefused) as refused:
        check_waypoints("bob", JOINTS, times, positions, velocities)
    text = str(refused.value)
    assert text.startswith("bob: trajectory refused: ") and word in text and "\n" not in text
