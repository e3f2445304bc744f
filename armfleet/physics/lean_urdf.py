"""The URDF PyBullet is given for an arm: its description without landmark links.

A landmark link (``world``, ``base_link``, ``tool0``, ``tcp``, upstream's massless
``panda_link8`` and ``panda_hand_tcp`` ...) has no mass and no collision shape and
hangs on a fixed joint. It names a frame; it is nothing the physics has to move.
Yet PyBullet's Featherstone solver pays for every link of a multibody at every
step, mass or not (about 1.3 µs per link per arm per step on the development
machine: ``docs/performance.md``). So the body PyBullet simulates leaves them out:

- a landmark inside the tree is removed, and its children hang on its parent with
  the two fixed joints' origins composed;
- a landmark root (``world``, then ``base_link``) is removed while it has exactly one
  child on a fixed joint; the first link that stays becomes the base, placed at
  the composed transform (:attr:`LeanUrdf.base_pose`).

Nothing else changes: every link with mass or a collision shape keeps its name,
its inertial, its collisions and its place in the world; every movable joint
stays. The landmark frames live on in the Pinocchio model and on TF, which are
built from the full description.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from armfleet.errors import DescriptionError
from armfleet.messages import FloatArray


@dataclass(frozen=True)
class LeanUrdf:
    """An arm's URDF without landmark links.

    Attributes:
        text: the URDF text to load.
        base_link: its root link (PyBullet's base, link index -1).
        base_pose: 4x4 pose of :attr:`base_link` in the frame of the full
            description's root (the world, for an armfleet description).
        removed: the landmark links left out, in document order.
    """

    text: str
    base_link: str
    base_pose: FloatArray
    removed: tuple[str, ...]


def lean_urdf(urdf: str) -> LeanUrdf:
    """``urdf`` without its landmark links (see the module docstring).

    Raises:
        DescriptionError: the text is not a URDF with one root link.
    """
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"the URDF is not valid XML: {exc}") from exc
    links = {link.get("name", ""): link for link in robot.findall("link")}
    joints = robot.findall("joint")
    parent_joint = {_child(joint): joint for joint in joints}
    roots = [name for name in links if name not in parent_joint]
    if len(roots) != 1:
        raise DescriptionError(f"a URDF has one root link, this one has {roots or 'none'}")
    root = roots[0]
    removed: list[str] = []
    for name, link in links.items():
        joint = parent_joint.get(name)
        if name == root or joint is None or not _is_landmark(link, joint):
            continue
        for child_joint in _child_joints(joints, name):
            child_joint.find("parent").set("link", _parent(joint))  # type: ignore[union-attr]
            _set_origin(child_joint, _origin(joint) @ _origin(child_joint))
        robot.remove(link)
        robot.remove(joint)
        joints.remove(joint)
        removed.append(name)
    base_pose = np.eye(4)
    while _is_landmark(links[root], None):
        children = _child_joints(joints, root)
        if len(children) != 1 or children[0].get("type") != "fixed":
            break
        joint = children[0]
        base_pose = base_pose @ _origin(joint)
        robot.remove(links[root])
        robot.remove(joint)
        joints.remove(joint)
        removed.append(root)
        root = _child(joint)
    text = ET.tostring(robot, encoding="unicode")
    return LeanUrdf(text, root, base_pose, tuple(removed))


def _is_landmark(link: ET.Element, joint: ET.Element | None) -> bool:
    """No collision shape, no mass, and (if it has a parent) a fixed joint to it."""
    if link.find("collision") is not None:
        return False
    mass = link.find("inertial/mass")
    if mass is not None and float(mass.get("value", "0")) > 0.0:
        return False
    return joint is None or joint.get("type") == "fixed"


def _child_joints(joints: list[ET.Element], link: str) -> list[ET.Element]:
    return [joint for joint in joints if _parent(joint) == link]


def _parent(joint: ET.Element) -> str:
    return _link_of(joint, "parent")


def _child(joint: ET.Element) -> str:
    return _link_of(joint, "child")


def _link_of(joint: ET.Element, tag: str) -> str:
    element = joint.find(tag)
    if element is None or not element.get("link"):
        raise DescriptionError(f"joint {joint.get('name')!r} has no <{tag} link=...>")
    return element.get("link", "")


def _origin(joint: ET.Element) -> FloatArray:
    """The joint's ``<origin>`` as a 4x4 matrix (identity when absent)."""
    origin = joint.find("origin")
    xyz = np.zeros(3)
    rpy = np.zeros(3)
    if origin is not None:
        xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        rpy = np.array([float(v) for v in origin.get("rpy", "0 0 0").split()])
    matrix = np.eye(4)
    matrix[:3, :3] = pin.rpy.rpyToMatrix(rpy)
    matrix[:3, 3] = xyz
    return matrix


def _set_origin(joint: ET.Element, matrix: FloatArray) -> None:
    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    rpy = pin.rpy.matrixToRpy(matrix[:3, :3])
    origin.set("xyz", " ".join(repr(float(v)) for v in matrix[:3, 3]))
    origin.set("rpy", " ".join(repr(float(v)) for v in rpy))
