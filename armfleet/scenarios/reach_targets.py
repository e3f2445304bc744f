"""Random reachable targets of an arm: tool0 poses of random joint configurations.

A target is where tool0 is, by the arm's forward kinematics, at a joint configuration
drawn uniformly within the joint limits less a margin (a fraction of each joint's range,
as :mod:`armfleet.kinematics.inverse_kinematics` keeps its solutions off the limits), and kept only
if the arm could rest there:

- tool0 at least ``min_tool_height_m`` above the floor (the hand and fingers hang up to
  ~0.11 m beyond it);
- the arm touches neither itself nor the floor there, by the rule that admits an arm at
  its start pose (:mod:`armfleet.physics.start_clearance`: 1 mm, the link pairs the contact
  monitor counts), asked of PyBullet in a scratch client that holds only a floor and a
  copy of the arm (:class:`ClearanceProbe`); the world is not touched.

Other arms are not considered: whether neighbours get in each other's way on the way
to their targets is what a sweep of :mod:`armfleet.scenarios.reach` measures.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import TracebackType

import numpy as np
import pybullet as p

from armfleet.arms.arm import Arm
from armfleet.checks.real_numbers import real_number
from armfleet.errors import ArmfleetError
from armfleet.kinematics.continuous_joints import one_turn_bounds
from armfleet.messages import FloatArray
from armfleet.physics.arm_body import ArmBody
from armfleet.physics.contact_monitor import GROUND
from armfleet.physics.ground import create_ground
from armfleet.physics.start_clearance import BodyKind, Neighbour, start_contacts

#: Configurations drawn per target before giving up (about 9 in 10 are kept for a Panda).
MAX_DRAWS_PER_TARGET = 1000


@dataclass(frozen=True)
class Target:
    """A pose to reach and the configuration it came from.

    Attributes:
        arm: the arm's name.
        positions: the drawn joint configuration, one per ``arm.joint_names`` [rad].
        pose: 4x4 world pose of the arm's tool0 at ``positions`` [m].
    """

    arm: str
    positions: FloatArray
    pose: FloatArray


class ClearanceProbe:
    """A scratch PyBullet client with a floor and a copy of ``arm``: whether a configuration
    of the arm touches itself or the floor. Use it in a ``with`` block (it disconnects).

    Args:
        arm: the arm to copy (its description, at its spawn pose; the fingers as they are).
    """

    def __init__(self, arm: Arm) -> None:
        self._name = arm.name
        self._ignored = arm.description.ignored_contacts
        self._columns = arm.kinematics.arm_indices
        self._q = arm.body.position.copy()
        self._client: int = p.connect(p.DIRECT)
        try:
            floor = create_ground(self._client)
            self._floor = Neighbour(floor, GROUND, {-1: ""}, BodyKind.GROUND, frozenset({-1}))
            self._body = ArmBody(self._client, arm.description.urdf, arm.kinematics.joint_names)
        except BaseException:
            p.disconnect(physicsClientId=self._client)
            raise

    def touches(self, positions: FloatArray) -> bool:
        """Whether the arm at ``positions`` (its :attr:`Arm.joint_names`) [rad] comes within
        1 mm of itself or the floor (links resting on the floor excepted)."""
        q = self._q.copy()
        q[self._columns] = positions
        self._body.reset(q)
        contacts = start_contacts(
            self._client, self._name, self._body, self._ignored, [self._floor]
        )
        return bool(contacts)

    def close(self) -> None:
        p.disconnect(physicsClientId=self._client)

    def __enter__(self) -> ClearanceProbe:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def tool_pose(arm: Arm, positions: FloatArray) -> FloatArray:
    """4x4 world pose of ``arm``'s tool0 with its joints at ``positions`` [rad]; the
    fingers as they are."""
    q = arm.body.position.copy()
    q[arm.kinematics.arm_indices] = positions
    pose: FloatArray = np.array(arm.ik.frame_pose(arm.description.tool0, q).homogeneous)
    return pose


def draw_targets(
    arm: Arm,
    rng: np.random.Generator,
    count: int,
    *,
    limit_margin: float = 0.1,
    min_tool_height_m: float = 0.1,
    probe: ClearanceProbe | None = None,
) -> list[Target]:
    """``count`` targets of ``arm``, drawn with ``rng`` (see the module docstring).

    Args:
        arm: the arm (its joint limits, kinematics and description).
        rng: the run's generator; the draws depend on nothing else.
        count: targets to draw, >= 0.
        limit_margin: fraction of each joint's range kept clear of either limit, in [0, 0.45].
        min_tool_height_m: lowest tool0 height above the floor [m].
        probe: a probe of ``arm``, or of another arm of its model standing upright on
            the floor (contacts with itself and the floor do not change with the base's
            x, y and yaw); by default one is made for this call (~25 ms).

    Raises:
        ArmfleetError: a bad argument, or :data:`MAX_DRAWS_PER_TARGET` draws per target
            gave too few (the margin or the height leaves the arm no room).
    """
    margin = real_number(limit_margin, "limit_margin", "a fraction in [0, 0.45]", low=0, high=0.45)
    height = real_number(
        min_tool_height_m, "min_tool_height_m", "a height in [-1, 1] m", low=-1, high=1
    )
    if probe is None:
        with ClearanceProbe(arm) as own:
            return draw_targets(
                arm, rng, count, limit_margin=margin, min_tool_height_m=height, probe=own
            )
    lower, upper = one_turn_bounds(*arm.joint_limits)  # a continuous joint: one turn
    span = upper - lower
    low, high = lower + margin * span, upper - margin * span
    targets: list[Target] = []
    for _ in range(MAX_DRAWS_PER_TARGET * count):
        if len(targets) == count:
            break
        positions = rng.uniform(low, high)
        pose = tool_pose(arm, positions)
        if pose[2, 3] < height or probe.touches(positions):
            continue
        targets.append(Target(arm.name, positions, pose))
    if len(targets) < count:
        raise ArmfleetError(
            f"{arm.name}: only {len(targets)} of {count} targets clear of itself and the floor "
            f"with tool0 above {min_tool_height_m} m in {MAX_DRAWS_PER_TARGET * count} draws; "
            "lower limit_margin or min_tool_height_m"
        )
    return targets


def pose_error(actual: FloatArray, wanted: FloatArray) -> tuple[float, float]:
    """(distance [m], rotation angle [rad]) between two 4x4 poses."""
    distance = float(np.linalg.norm(actual[:3, 3] - wanted[:3, 3]))
    rotation = wanted[:3, :3].T @ actual[:3, :3]
    axis = np.array(
        [
            rotation[2, 1] - rotation[1, 2],
            rotation[0, 2] - rotation[2, 0],
            rotation[1, 0] - rotation[0, 1],
        ]
    )
    angle = float(np.arctan2(0.5 * np.linalg.norm(axis), 0.5 * (np.trace(rotation) - 1.0)))
    return distance, angle


def draw_row_targets(
    arms: Sequence[Arm],
    rng: np.random.Generator,
    count: int,
    *,
    limit_margin: float = 0.1,
    min_tool_height_m: float = 0.1,
    probe: ClearanceProbe | None = None,
) -> dict[str, list[Target]]:
    """``count`` targets for each of ``arms`` (in order, by name), drawn with ``rng``.

    The arms must be of one model and stand upright on the floor: they share one
    :class:`ClearanceProbe`, ``probe`` (kept by a caller that draws often: making one
    costs ~20 ms) or one made of the first arm for this call.
    """
    if not arms:
        return {}
    if probe is None:
        with ClearanceProbe(arms[0]) as own:
            return draw_row_targets(
                arms, rng, count, limit_margin=limit_margin,
                min_tool_height_m=min_tool_height_m, probe=own,
            )  # fmt: skip
    return {
        arm.name: draw_targets(
            arm, rng, count, limit_margin=limit_margin,
            min_tool_height_m=min_tool_height_m, probe=probe,
        )
        for arm in arms
    }  # fmt: skip
