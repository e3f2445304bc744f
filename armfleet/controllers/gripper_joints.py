"""Which joints a gripper drives: its leaders (commanded) and its followers (mimics).

The joints are the description's ``gripper_joints`` when it names any (a model file's
anatomy: mimic joints and joints named like fingers), else the shipped models' rule:
the prismatic joints off the base_link -> tool0 chain (the Panda's two fingers, all
leaders). A joint with ``<mimic joint="x" multiplier="m" offset="o"/>`` whose ``x`` is
also a gripper joint follows it: the gripper controller drives it to ``m q_x + o`` at
every step (PyBullet does not enforce ``<mimic>``), and it is never commanded on its own.
A mimic of a mimic follows the first leader (the multipliers and offsets composed).

Pinocchio (4.1, ``buildModelFromXML`` without ``mimic=True``) keeps a mimic joint as a
joint of its own, with its own q: the model has one independent q per movable joint, as
the rest of armfleet assumes, and the coupling is the gripper controller's.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from armfleet.errors import DescriptionError
from armfleet.kinematics import ArmKinematics

#: Pinocchio joint types of a prismatic finger (along any axis) and of a revolute jaw.
PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")
REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")


@dataclass(frozen=True)
class Follower:
    """A joint driven to ``multiplier * q[leader] + offset``.

    Attributes:
        index: its index into q.
        leader: the index (into q) of the joint it follows.
        multiplier, offset: the ``<mimic>``'s (composed along a chain of mimics).
    """

    index: int
    leader: int
    multiplier: float
    offset: float


@dataclass(frozen=True)
class GripperJoints:
    """A gripper's joints.

    Attributes:
        leaders: indices (into q) of the joints the commands drive, in q order.
        followers: the mimic joints, which follow a leader.
        revolute: whether the leaders are revolute jaws (else prismatic fingers).
        anvil: the link a single moving jaw closes against (the link it hangs from), or
            None when two or more links move.
    """

    leaders: npt.NDArray[np.int_]
    followers: tuple[Follower, ...] = ()
    revolute: bool = False
    anvil: str | None = None

    @property
    def indices(self) -> npt.NDArray[np.int_]:
        """Every joint of the gripper (leaders and followers), in q order."""
        every = [*self.leaders.tolist(), *(f.index for f in self.followers)]
        return np.array(sorted(every), dtype=int)


def gripper_joints(
    kinematics: ArmKinematics, urdf: str = "", named: Sequence[str] = ()
) -> GripperJoints:
    """The gripper's joints: ``named`` (prefixed joint names; their ``<mimic>`` read
    from ``urdf``) or, when ``named`` is empty, the prismatic joints off the arm chain.

    Raises:
        DescriptionError: a named joint is not a movable joint off the arm chain, is
            neither prismatic nor revolute, or the leaders mix prismatic and revolute.
    """
    if not named:
        return GripperJoints(_inferred_fingers(kinematics))
    indices = [_index_of(kinematics, name) for name in named]
    mimics, parents = _mimics_and_parents(urdf)
    by_name = dict(zip(named, indices, strict=True))

    def root(name: str) -> tuple[str, float, float]:
        """The leader ``name`` follows (itself if none), and the composed mimic."""
        multiplier, offset, seen = 1.0, 0.0, {name}
        while name in mimics and mimics[name][0] in by_name and mimics[name][0] not in seen:
            leader, m, o = mimics[name]
            multiplier, offset, name = m * multiplier, m * offset + o, leader
            seen.add(name)
        return name, multiplier, offset

    followers, leaders = [], set()
    for name in named:
        leader, multiplier, offset = root(name)
        if leader == name:
            leaders.add(by_name[name])
        else:
            followers.append(Follower(by_name[name], by_name[leader], multiplier, offset))
    kinds = {_kind(kinematics, index) for index in leaders}
    if len(kinds) > 1:
        raise DescriptionError(
            f"gripper joints {', '.join(named)} mix prismatic and revolute leaders; a "
            "gripper's opening is measured in one unit: give the joints of one kind"
        )
    moving = [kinematics.joint_names[i] for i in sorted(leaders | {f.index for f in followers})]
    anvil = parents.get(moving[0]) if len(moving) == 1 else None
    return GripperJoints(
        np.array(sorted(leaders), dtype=int), tuple(followers), kinds == {"revolute"}, anvil
    )


def _inferred_fingers(kinematics: ArmKinematics) -> npt.NDArray[np.int_]:
    model = kinematics.model
    fingers = [
        model.joints[j].idx_q
        for j in range(1, model.njoints)
        if model.joints[j].idx_q in kinematics.auxiliary_indices
        and model.joints[j].shortname() in PRISMATIC
    ]
    return np.array(fingers, dtype=int)


def _index_of(kinematics: ArmKinematics, name: str) -> int:
    off_chain = [kinematics.joint_names[i] for i in kinematics.auxiliary_indices]
    if name not in off_chain:
        raise DescriptionError(
            f"gripper joint {name!r} is not a movable joint off the arm chain; valid: "
            f"{', '.join(off_chain) or 'none'}"
        )
    index = kinematics.joint_names.index(name)
    _kind(kinematics, index)
    return index


def _kind(kinematics: ArmKinematics, index: int) -> str:
    model = kinematics.model
    joint = next(model.joints[j] for j in range(1, model.njoints) if model.joints[j].idx_q == index)
    if joint.shortname() in PRISMATIC:
        return "prismatic"
    if joint.shortname() in REVOLUTE:
        return "revolute"
    name = kinematics.joint_names[index]
    raise DescriptionError(f"gripper joint {name!r} is neither prismatic nor revolute")


def _mimics_and_parents(
    urdf: str,
) -> tuple[dict[str, tuple[str, float, float]], dict[str, str]]:
    """Per joint of ``urdf``: the ``<mimic>`` it has (leader, multiplier, offset), and
    its parent link."""
    mimics: dict[str, tuple[str, float, float]] = {}
    parents: dict[str, str] = {}
    if not urdf:
        return mimics, parents
    for joint in ET.fromstring(urdf).findall("joint"):
        name = joint.get("name", "")
        parent = joint.find("parent")
        if parent is not None:
            parents[name] = parent.get("link", "")
        mimic = joint.find("mimic")
        if mimic is not None:
            multiplier = float(mimic.get("multiplier", "1") or 1)
            offset = float(mimic.get("offset", "0") or 0)
            mimics[name] = (mimic.get("joint", ""), multiplier, offset)
    return mimics, parents


def finger_indices(kinematics: ArmKinematics, named: Sequence[str] = ()) -> npt.NDArray[np.int_]:
    """Indices (into q) of every joint of the arm's gripper, leaders and followers:
    ``named`` (prefixed names) or, when it is empty, the prismatic joints off the
    base-tool chain.

    Raises:
        DescriptionError: a named joint is not a prismatic or revolute joint off the
            arm chain.
    """
    if not named:
        return _inferred_fingers(kinematics)
    return np.array(sorted(_index_of(kinematics, name) for name in named), dtype=int)
