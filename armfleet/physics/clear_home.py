"""A home pose for an arm whose description gives none: clear of itself and of the floor.

The preferred pose (every arm joint at zero, clamped into its limits) is taken if PyBullet
finds it touching neither itself (links not joined to each other) nor the floor. Else
configurations drawn around it within the limits, a little first, then further (a fixed
seed, so the same description always gets the same home), are tried nearest first, and the
first clear one is the home.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as p

from armfleet.errors import DescriptionError
from armfleet.messages import FloatArray
from armfleet.physics.lean_urdf import lean_urdf
from armfleet.physics.start_clearance import CLEARANCE_M

#: How far from the preferred pose configurations are drawn, nearest first [rad or m].
REACHES_RAD = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
#: Configurations drawn per reach when the preferred one is not clear.
CANDIDATES_PER_REACH = 300
CANDIDATES = CANDIDATES_PER_REACH * len(REACHES_RAD)
SEED = 7
#: Clearance a home keeps between links not joined to each other [m]: the spawn's (an
#: arm's wrist links sit within millimetres of each other by design).
SELF_MARGIN_M = CLEARANCE_M
#: Clearance a home keeps from the floor [m], for links three or more movable joints from
#: the base (the forearm on): a home is a pose to move from, not one at the floor. Links
#: nearer the base stay near the floor whatever the pose, and only keep the spawn's. A small
#: arm keeps :data:`FLOOR_SHARE` of its length instead, if that is less.
FLOOR_MARGIN_M = 0.2
FLOOR_SHARE = 0.25


@dataclass(frozen=True)
class Home:
    """The home chosen and why: ``reason`` names what made the preferred one unusable."""

    positions: tuple[float, ...]
    preferred: bool
    reason: str = ""


def clear_home(
    urdf: str, arm_joints: Sequence[str], preferred: Sequence[float], search: bool = True
) -> Home:
    """A home of ``arm_joints`` (URDF joint names, in chain order) for ``urdf`` (URIs resolved,
    the arm's root at the origin), preferring ``preferred``.

    With ``search`` False, ``preferred`` is a home the user gave: it is the home if it is
    clear as a spawn's start pose is (no link nearer itself or the floor than
    :data:`SELF_MARGIN_M`), and nothing else is tried.

    Raises:
        DescriptionError: no drawn configuration is clear either; without ``search``, the
            given home is not clear (what it touches named).
    """
    lean = lean_urdf(urdf)
    client = p.connect(p.DIRECT)
    fd, path = tempfile.mkstemp(suffix=".urdf", prefix="armfleet-home-")
    try:
        with os.fdopen(fd, "w") as file:
            file.write(lean.text)
        floor = p.createMultiBody(
            0.0,
            p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client),
            physicsClientId=client,
        )
        body = p.loadURDF(
            path, useFixedBase=True, flags=p.URDF_USE_SELF_COLLISION, physicsClientId=client
        )
        position = lean.base_pose[:3, 3]
        p.resetBasePositionAndOrientation(
            body, position.tolist(), [0, 0, 0, 1], physicsClientId=client
        )
        indices, lower, upper = _arm_joints(client, body, arm_joints)
        _others_mid_range(client, body, indices)  # as the arm is assembled: fingers half open
        joined = _joined_pairs(client, body)
        margin = min(FLOOR_MARGIN_M, FLOOR_SHARE * _length(client, body))
        margin = margin if search else SELF_MARGIN_M
        start = np.asarray(preferred, dtype=float)
        problem = _touching(client, body, floor, indices, start, joined, margin)
        if problem is None:
            return Home(tuple(float(v) for v in start), True)
        if not search:
            shown = ", ".join(f"{v:g}" for v in start)
            raise DescriptionError(
                f"home: [{shown}] touches {problem} (within {SELF_MARGIN_M * 1e3:g} mm); "
                "give a home clear of the arm itself and the floor"
            )
        rng = np.random.default_rng(SEED)
        for reach in REACHES_RAD:  # nearest first: small changes of the preferred pose
            drawn = np.clip(
                start + rng.uniform(-reach, reach, size=(CANDIDATES_PER_REACH, len(indices))),
                lower,
                upper,
            )
            for candidate in drawn[np.argsort(np.abs(drawn - start).max(axis=1))]:
                if _touching(client, body, floor, indices, candidate, joined, margin) is None:
                    return Home(tuple(float(v) for v in candidate), False, problem)
        raise DescriptionError(
            f"no clear home found: the zero pose touches {problem}, and so did "
            f"{CANDIDATES} poses drawn within the limits; give home: explicitly"
        )
    finally:
        os.unlink(path)
        p.disconnect(client)


def _arm_joints(
    client: int, body: int, names: Sequence[str]
) -> tuple[list[int], FloatArray, FloatArray]:
    found: dict[str, tuple[int, float, float]] = {}
    for index in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, index, physicsClientId=client)
        found[info[1].decode()] = (index, float(info[8]), float(info[9]))
    missing = [name for name in names if name not in found]
    if missing:
        raise DescriptionError(f"arm joints {', '.join(missing)} are not in the simulated body")
    indices = [found[name][0] for name in names]
    lower = np.array([found[name][1] for name in names])
    upper = np.array([found[name][2] for name in names])
    return indices, lower, upper


def _others_mid_range(client: int, body: int, arm: list[int]) -> None:
    for index in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, index, physicsClientId=client)
        lower, upper = float(info[8]), float(info[9])
        if index not in arm and info[2] != p.JOINT_FIXED and lower <= upper:
            p.resetJointState(body, index, (lower + upper) / 2, physicsClientId=client)


def _joined_pairs(client: int, body: int) -> set[tuple[int, int]]:
    """Link pairs of one rigid piece or one movable joint apart (as the world's collision
    filter ignores them: :mod:`armfleet.physics.collision_filter`), lower index first."""
    piece: dict[int, int] = {-1: -1}
    parent_piece: dict[int, int] = {-1: -1}
    for link in range(p.getNumJoints(body, physicsClientId=client)):  # parents come first
        info = p.getJointInfo(body, link, physicsClientId=client)
        parent = info[16]
        moves = info[2] != p.JOINT_FIXED
        piece[link] = link if moves else piece[parent]
        parent_piece[link] = piece[parent] if moves else parent_piece[parent]
    links = sorted(piece)
    return {
        (a, b)
        for i, a in enumerate(links)
        for b in links[i + 1 :]
        if piece[a] == piece[b]
        or parent_piece[piece[b]] == piece[a]
        or parent_piece[piece[a]] == piece[b]
    }


def _touching(
    client: int,
    body: int,
    floor: int,
    indices: list[int],
    positions: FloatArray,
    joined: set[tuple[int, int]],
    floor_margin_m: float,
) -> str | None:
    """What the body touches or nears at ``positions`` ("itself (a / b)", "the floor (a)"),
    within the margins, or None."""
    for index, value in zip(indices, positions, strict=True):
        p.resetJointState(body, index, float(value), physicsClientId=client)
    p.performCollisionDetection(physicsClientId=client)
    for point in p.getClosestPoints(body, body, SELF_MARGIN_M, physicsClientId=client):
        pair = (min(point[3], point[4]), max(point[3], point[4]))
        if point[3] != point[4] and pair not in joined:
            return f"itself ({_link(client, body, point[3])} / {_link(client, body, point[4])})"
    near = p.getClosestPoints(body, floor, floor_margin_m, physicsClientId=client)
    for point in near:
        link = point[3]
        if link == -1:  # the base stands on the floor
            continue
        above = _movable_joints_above(client, body, link)
        if above >= 3 or (above == 2 and point[8] <= SELF_MARGIN_M):
            return f"the floor ({_link(client, body, link)})"
    return None


def _length(client: int, body: int) -> float:
    """The arm's length [m]: the offsets of all its joints, end to end."""
    return sum(
        float(np.linalg.norm(p.getJointInfo(body, index, physicsClientId=client)[14]))
        for index in range(p.getNumJoints(body, physicsClientId=client))
    )


def _movable_joints_above(client: int, body: int, link: int) -> int:
    count = 0
    while link != -1:
        info = p.getJointInfo(body, link, physicsClientId=client)
        count += info[2] != p.JOINT_FIXED
        link = info[16]  # its parent
    return count


def _link(client: int, body: int, index: int) -> str:
    if index == -1:
        return str(p.getBodyInfo(body, physicsClientId=client)[0].decode())
    return str(p.getJointInfo(body, index, physicsClientId=client)[12].decode())
