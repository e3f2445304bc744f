"""Inverse kinematics of one arm: damped least squares within the joint limits.

The solver moves only the arm joints (``ArmKinematics.arm_indices``); the other
movable joints (fingers) keep the values of the seed. Each iteration takes the
frame error ``log6(oMf^-1 oMdes)`` in the frame's own axes and the step

    dq = J^T (J J^T + lambda I)^-1 e,    J = -Jlog6 J_local,    lambda = 1e-6 + 1e-2 |e|^2

(the damping fades as the error does, so the last iterations are Gauss-Newton),
limited to ``max_step_rad`` per joint and clamped to the joint limits. A
redundant arm (more than 6 joints) also moves in the task's null space
``(I - J^+ J)`` away from any joint within 10 % of its range from a limit
(while the error is above 0.1 mm or mrad: damping makes that step not quite
null, so it stops for the last iterations), so
that a sequence of warm-started solves (a straight line) does not run a joint
into its limit when the other joints could make way. The seed
is tried first, so a reachable pose near the seed gives the solution near it.
Only if that attempt fails (DLS cannot cross a singularity, e.g. a UR's elbow
from bent one way to the other) are up to ``max_restarts`` random in-limit
configurations tried, the k-th within ``k * restart_spread_rad`` of the seed
in each joint, so that nearer solutions come first (drawn from a generator
seeded per call: a solve is deterministic). An attempt gives up when its error
has not halved for 10 iterations.

A continuous joint has no limit to clamp to or keep away from; its angle in the solution
is the equivalent one nearest the seed's (within ±pi of it), so the arm turns it the short
way and it never drifts by whole turns.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from armfleet.checks.number_ranges import WORLD_COORDINATE_M
from armfleet.checks.real_numbers import all_real
from armfleet.errors import TargetPoseError, UnknownFrame
from armfleet.kinematics import ArmKinematics
from armfleet.kinematics.arm_kinematics import body_frame_id
from armfleet.kinematics.continuous_joints import nearest_turn
from armfleet.messages import FloatArray

#: Orthonormality and last-row tolerance of a 4x4 pose given by a user.
POSE_TOLERANCE = 1e-6
_STALL_ITERATIONS = 10
#: Below this error [m or rad] the null-space push stops, so the last iterations converge.
_NULL_SPACE_ERROR = 1e-4


def is_pose(target: Any) -> bool:
    """Whether ``target`` is a pose (4x4 or ``pinocchio.SE3``) rather than joint positions."""
    return isinstance(target, pin.SE3) or np.ndim(target) == 2


def as_se3(pose: Any) -> pin.SE3:
    """``pose`` (a 4x4 homogeneous matrix or a ``pinocchio.SE3``) as an SE3.

    Raises:
        TargetPoseError: not 4x4, not finite, or not a rigid transform.
    """
    if isinstance(pose, pin.SE3):
        pose = pose.homogeneous  # checked as any matrix: pin.SE3 takes any 3x3 and NaN
    if not all_real(pose):
        raise TargetPoseError("a pose must be a 4x4 homogeneous matrix of numbers (or a pin.SE3)")
    try:
        matrix = np.asarray(pose, dtype=float)
    except ValueError:  # ragged rows
        raise TargetPoseError("a pose must be a 4x4 homogeneous matrix of numbers") from None
    if matrix.shape != (4, 4):
        raise TargetPoseError(f"a pose must be a 4x4 homogeneous matrix, got shape {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise TargetPoseError("a pose must be finite (it has NaN or inf)")
    if not all(WORLD_COORDINATE_M.contains(float(v)) for v in matrix[:3, 3]):
        raise TargetPoseError(
            f"a pose's position {matrix[:3, 3].tolist()} is out of range; give "
            f"{WORLD_COORDINATE_M.valid} each"
        )
    rotation = matrix[:3, :3]
    if (
        np.abs(rotation.T @ rotation - np.eye(3)).max() > POSE_TOLERANCE
        or np.linalg.det(rotation) < 0
        or np.abs(matrix[3] - [0.0, 0.0, 0.0, 1.0]).max() > POSE_TOLERANCE
    ):
        raise TargetPoseError(
            "a pose's upper-left 3x3 must be a rotation (orthonormal, det +1) and its "
            "last row 0 0 0 1"
        )
    return pin.SE3(rotation.copy(), matrix[:3, 3].copy())


def world_goal(pose: Any, frame: str, frame_pose: Callable[[str], FloatArray] | None) -> pin.SE3:
    """``pose`` given in ``frame`` as a world pose; ``frame_pose`` gives a frame's world pose."""
    goal = as_se3(pose)
    if frame == "world":
        return goal
    if frame_pose is None:
        raise UnknownFrame(frame, "this arm has no frame resolver; give a world pose")
    return pin.SE3(frame_pose(frame)) * goal


def link_frame(arm: str, kinematics: ArmKinematics, prefix: str, link: str) -> str:
    """The prefixed frame of ``link`` (given with or without the arm's prefix)."""
    name = prefix + link.removeprefix(prefix) if isinstance(link, str) else ""
    if not name or not kinematics.has_frame(name):
        links = (n.removeprefix(prefix) for n in kinematics.link_names if n != "world")
        raise UnknownFrame(link, f"links of {arm}: {', '.join(sorted(links))}")
    return name


@dataclass(frozen=True)
class IkSolution:
    """The outcome of one solve.

    Attributes:
        positions: every movable joint [rad or m] (the best found if not converged).
        converged: whether both residuals are within the tolerances.
        position_error_m: distance of the frame from the target [m].
        rotation_error_rad: angle between the frame's and the target's orientation [rad].
        iterations: iterations over all attempts.
        restarts: attempts from random configurations after the seeded one.
    """

    positions: FloatArray
    converged: bool
    position_error_m: float
    rotation_error_rad: float
    iterations: int
    restarts: int


class InverseKinematics:
    """DLS inverse kinematics on an arm's Pinocchio model (its own data: the
    model's cached forward kinematics, used by the TF tree, is left alone).

    Args:
        kinematics: the arm's model.
        position_tolerance_m, rotation_tolerance_rad: convergence thresholds.
        max_iterations: per attempt.
        max_restarts: random restarts after a failed seeded attempt.
        max_step_rad: largest change of one joint in one iteration [rad or m].
        restart_spread_rad: growth of the restarts' distance from the seed [rad or m].
    """

    def __init__(
        self,
        kinematics: ArmKinematics,
        *,
        position_tolerance_m: float = 1e-6,
        rotation_tolerance_rad: float = 1e-6,
        max_iterations: int = 60,
        max_restarts: int = 20,
        max_step_rad: float = 0.5,
        restart_spread_rad: float = 0.25,
    ) -> None:
        self._model = kinematics.model
        self._data = self._model.createData()
        self._arm = kinematics.arm_indices
        self._lower = kinematics.lower[self._arm]
        self._upper = kinematics.upper[self._arm]
        self.position_tolerance_m = position_tolerance_m
        self.rotation_tolerance_rad = rotation_tolerance_rad
        self.max_iterations = max_iterations
        self.max_restarts = max_restarts
        self.max_step_rad = max_step_rad
        self.restart_spread_rad = restart_spread_rad
        self._continuous = kinematics.continuous[self._arm]
        self._redundant = self._arm.size > 6
        # A redundant arm's joint within 10 % of its range from a limit is pushed back,
        # from below these [rad or m]: never a continuous one (it has no limit).
        margin = np.where(self._continuous, 1.0, 0.1 * (self._upper - self._lower))
        self._margin = margin
        self._pushed_below = np.where(self._continuous, -np.inf, self._lower + margin)
        self._pushed_above = np.where(self._continuous, np.inf, self._upper - margin)

    def frame_pose(self, frame: str, q: FloatArray) -> pin.SE3:
        """World pose of ``frame`` at configuration ``q`` (every movable joint)."""
        frame_id = body_frame_id(self._model, frame)
        pin.framesForwardKinematics(self._model, self._data, q)
        return pin.SE3(self._data.oMf[frame_id])

    def solve(
        self, frame: str, target: pin.SE3, seed: FloatArray, *, restarts: bool = True
    ) -> IkSolution:
        """Joint positions that put ``frame`` at the world pose ``target``.

        Args:
            frame: a frame of the model (prefixed name).
            target: the wanted world pose.
            seed: every movable joint [rad or m]; the first guess for the arm joints
                and the fixed value of the others.
            restarts: try random configurations if the seeded attempt fails.
        """
        frame_id = body_frame_id(self._model, frame)
        best = self._attempt(frame_id, target, np.array(seed, dtype=float))
        iterations, tries = best[4], 0
        generator = np.random.default_rng(0)
        while not best[1] and restarts and tries < self.max_restarts:
            tries += 1
            start = np.array(seed, dtype=float)
            spread = tries * self.restart_spread_rad
            start[self._arm] = generator.uniform(
                np.maximum(start[self._arm] - spread, self._lower),
                np.minimum(start[self._arm] + spread, self._upper),
            )
            result = self._attempt(frame_id, target, start)
            iterations += result[4]
            if result[1] or result[2] + result[3] < best[2] + best[3]:
                best = result
        q, converged, position_error, rotation_error, _ = best
        arm = self._arm
        q[arm] = nearest_turn(q[arm], np.asarray(seed, dtype=float)[arm], self._continuous)
        return IkSolution(q, converged, position_error, rotation_error, iterations, tries)

    def _attempt(
        self, frame_id: int, target: pin.SE3, q: FloatArray
    ) -> tuple[FloatArray, bool, float, float, int]:
        model, data, arm = self._model, self._data, self._arm
        best_error, stalled = np.inf, 0
        position_error = rotation_error = np.inf
        for iteration in range(self.max_iterations + 1):
            pin.computeJointJacobians(model, data, q)
            current = pin.updateFramePlacement(model, data, frame_id)
            frame_to_target = current.actInv(target)
            error = pin.log6(frame_to_target).vector
            position_error = float(np.linalg.norm(current.translation - target.translation))
            rotation_error = float(np.linalg.norm(error[3:]))
            if (
                position_error <= self.position_tolerance_m
                and rotation_error <= self.rotation_tolerance_rad
            ):
                return q, True, position_error, rotation_error, iteration
            squared = float(error @ error)
            if squared < 0.5 * best_error:
                best_error, stalled = squared, 0
            else:
                stalled += 1
                if stalled > _STALL_ITERATIONS:
                    break
            if iteration == self.max_iterations:
                break
            jacobian = pin.getFrameJacobian(model, data, frame_id, pin.ReferenceFrame.LOCAL)
            jacobian = -pin.Jlog6(frame_to_target.inverse()) @ jacobian[:, arm]
            damping = 1e-6 + 1e-2 * squared
            inverse = jacobian.T @ np.linalg.inv(jacobian @ jacobian.T + damping * np.eye(6))
            step = -inverse @ error
            if self._redundant and squared > _NULL_SPACE_ERROR**2:
                step += self._limit_avoidance(q[arm], inverse @ jacobian)
            largest = float(np.abs(step).max())
            if largest > self.max_step_rad:
                step *= self.max_step_rad / largest
            q[arm] = np.clip(q[arm] + step, self._lower, self._upper)
        return q, False, position_error, rotation_error, iteration

    def _limit_avoidance(self, q: FloatArray, projector: FloatArray) -> FloatArray:
        """A null-space step pushing joints near a limit back towards their range [rad]."""
        low = np.maximum(self._pushed_below - q, 0.0)
        high = np.maximum(q - self._pushed_above, 0.0)
        push = (low - high) / self._margin
        if not push.any():
            return np.zeros_like(q)
        null_step: FloatArray = 0.1 * (push - projector @ push)
        return null_step
