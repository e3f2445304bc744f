"""Helpers of the planning tests: the shared cell, goals, and what a run is watched for.

Everything here reads the world as PyBullet and the bus report it (``/collisions``,
controller state, object poses); nothing comes from the planner's own records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pybullet as p

import armfleet
from armfleet.messages import CollisionReport, FloatArray

#: A finished move ends within the controller's holding tolerance of its target [rad].
ARRIVAL_RAD = 1e-3
#: A settled arm's joints drift less than this over 0.2 s [rad] (tests/test_bad_input.py).
HOLD_DRIFT_RAD = 1e-4
#: The two-arm swap of the shared cell: each tool crosses to the other side of the post
#: (tool0 pointing down; toby faces bob). Its straight move_together hits the post.
BOB_SWAP_TOOL_M = (0.6, 0.15, 0.4)
TOBY_SWAP_TOOL_M = (0.3, -0.15, 0.4)


def tool_position(arm: armfleet.Arm, positions: FloatArray) -> FloatArray:
    """World position of ``arm``'s tool0 with its arm joints at ``positions`` [m]
    (Pinocchio's forward kinematics of its model, the other joints where they are)."""
    q = arm.body.position.copy()
    q[arm.kinematics.arm_indices] = positions
    return np.asarray(arm.ik.frame_pose(arm.description.tool0, q).translation, dtype=float)


def tool_down(xyz: tuple[float, float, float], yaw: float = 0.0) -> FloatArray:
    """A 4x4 world pose at ``xyz`` [m] with z pointing down, turned by ``yaw`` [rad]."""
    pose = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    pose[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.diag(
        [1.0, -1.0, -1.0]
    )
    pose[:3, 3] = xyz
    return pose


def shared_cell() -> armfleet.World:
    """Issue 16's cell (launch_specs/shared_cell.yaml), headless."""
    return armfleet.launch("shared_cell", viewer=False)


def swap_goals(world: armfleet.World) -> dict[str, FloatArray]:
    """Joint goals of the two-arm swap (IK of :data:`BOB_SWAP_TOOL_M` and
    :data:`TOBY_SWAP_TOOL_M`)."""
    return {
        "bob": world.arm("bob").solve_ik(tool_down(BOB_SWAP_TOOL_M)),
        "toby": world.arm("toby").solve_ik(tool_down(TOBY_SWAP_TOOL_M, math.pi)),
    }


@dataclass
class Watch:
    """Watches a world step by step: contacts of arms on ``/collisions``, which arms
    move, and the reference each controller follows.

    Args:
        world: the world.
        allowed: link pairs (sorted, as :attr:`Contact.pair`) whose contact is expected
            (a held object and the fingers that hold it).

    Attributes:
        contacts: contacts that involve an arm (body or link), outside ``allowed``,
            as (time [s], pair, depth [m]).
        moving: per step, per arm, whether its controller is moving.
        references: per step, per arm, the controller's reference position.
        stops: protective stops seen (world.safety.stops).
    """

    world: armfleet.World
    allowed: set[tuple[str, str]] = field(default_factory=set)
    contacts: list[tuple[float, tuple[str, str], float]] = field(default_factory=list)
    moving: list[dict[str, bool]] = field(default_factory=list)
    references: list[dict[str, FloatArray]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._stops_before = self.world.safety.stops
        self.world.bus.subscribe("/collisions", self._on_collisions)

    def _on_collisions(self, report: CollisionReport) -> None:
        arms = set(self.world.arms)
        for contact in report.contacts:
            if contact.body_a not in arms and contact.body_b not in arms:
                continue  # objects resting on objects: no arm involved
            if contact.pair in self.allowed:
                continue
            self.contacts.append((report.stamp, contact.pair, contact.depth))

    def __call__(self, world: armfleet.World) -> None:
        self.moving.append({name: arm.is_moving for name, arm in world.arms.items()})
        references = {}
        for name, arm in world.arms.items():
            trajectory = arm.position_controller.trajectory
            assert trajectory is not None
            references[name] = trajectory.position.copy()
        self.references.append(references)

    @property
    def stops(self) -> int:
        return self.world.safety.stops - self._stops_before

    def run(self, seconds: float) -> None:
        self.world.run(seconds, on_step=self)

    def first_step_moving(self, arm: str) -> int:
        """Index of the first watched step at which ``arm`` was moving."""
        return next(i for i, flags in enumerate(self.moving) if flags[arm])

    def last_step_moving(self, arm: str) -> int:
        """Index of the last watched step at which ``arm`` was moving."""
        return max(i for i, flags in enumerate(self.moving) if flags[arm])

    def first_step_leaving(self, arm: str, start: FloatArray) -> int:
        """Index of the first watched step whose reference has left ``start``."""
        return next(
            i for i, refs in enumerate(self.references) if np.abs(refs[arm] - start).max() > 1e-12
        )


def settle(world: armfleet.World, arms: list[armfleet.Arm], limit_s: float = 15.0) -> None:
    """Run until no arm of ``arms`` is moving (at most ``limit_s`` of simulated time)."""
    while any(arm.is_moving for arm in arms) and limit_s > 0:
        world.run(0.05)
        limit_s -= 0.05
    world.run(0.1)


def body_ids(world: armfleet.World) -> dict[str, int]:
    """PyBullet body ids by name: arms, objects and ``"ground"``."""
    return {n.name: n.body_id for n in world.contacts.neighbours()}


def gap(
    world: armfleet.World,
    body_a: str,
    body_b: str,
    window_m: float = 0.2,
    ids: dict[str, int] | None = None,
) -> float:
    """PyBullet's smallest distance between two bodies (arms or objects) [m], or
    ``window_m`` if they are further apart (``ids``: :func:`body_ids`, to save asking)."""
    ids = ids or body_ids(world)
    points = p.getClosestPoints(
        ids[body_a], ids[body_b], window_m, physicsClientId=world.physics_client
    )
    return float(min((point[8] for point in points), default=window_m))


def link_gap(world: armfleet.World, arm: str, link: str, body: str, window_m: float = 1.0) -> float:
    """PyBullet's distance [m] between link ``link`` of ``arm`` and the body ``body``."""
    client = world.physics_client
    ids = {n.name: n.body_id for n in world.contacts.neighbours()}
    own = world.arm(arm).body
    points = p.getClosestPoints(
        own.body_id, ids[body], window_m, own.link_index(link), -1, physicsClientId=client
    )
    return float(min((point[8] for point in points), default=window_m))


def gap_at(
    world: armfleet.World, positions: dict[str, FloatArray], body_a: str, body_b: str
) -> float:
    """PyBullet's distance [m] between ``body_a`` and ``body_b`` with the arms put at
    ``positions`` (per arm, its joints), in ``world``: a scratch world, the arms are put
    there without a step, then put back."""
    client = world.physics_client
    saved: list[tuple[int, int, float]] = []
    for arm, values in positions.items():
        body = world.arm(arm).body.body_id
        index = {
            p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
            for j in range(p.getNumJoints(body, physicsClientId=client))
        }
        for name, value in zip(world.arm(arm).joint_names, values, strict=True):
            joint = index[name]
            saved.append((body, joint, p.getJointState(body, joint, physicsClientId=client)[0]))
            p.resetJointState(body, joint, float(value), physicsClientId=client)
    distance = gap(world, body_a, body_b, 1.0)
    for body, joint, value in saved:
        p.resetJointState(body, joint, value, physicsClientId=client)
    return distance
