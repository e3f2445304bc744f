"""An arm and a separate gripper description made one robot, before armfleet prefixes it.

The gripper's expanded URDF is appended to the arm's: its ``world`` link and the joints
hanging from it are dropped, and a fixed joint ``<at_link>_end_effector_joint`` joins
the arm's link ``at_link`` to the gripper's root link. The two are then one description,
prefixed as one arm (``bob_...``), and the gripper's movable joints are the arm's
gripper joints. A link or joint named in both files is refused (prefixing would not tell
them apart), as is a gripper with more than one root.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

from armfleet.description.file_model import MOVABLE
from armfleet.errors import DescriptionError, ModelSettingError


@dataclass(frozen=True)
class ArmWithGripper:
    """The joined description and what the gripper brought.

    Attributes:
        urdf: the arm's URDF with the gripper's links and joints appended.
        gripper_joints: the gripper's movable joints, in its file's order.
        gripper_links: the gripper's links.
    """

    urdf: str
    gripper_joints: tuple[str, ...]
    gripper_links: tuple[str, ...]


def attach_end_effector(
    arm_urdf: str, gripper_urdf: str, at_link: str, source: str, gripper_source: str
) -> ArmWithGripper:
    """The arm (``arm_urdf``, from ``source``) with the gripper (``gripper_urdf``, from
    ``gripper_source``) fixed at its link ``at_link``.

    Raises:
        ModelSettingError: ``at_link`` is no link of the arm (its links listed), or a name
            is in both files.
        DescriptionError: the gripper is not a URDF or has no single root link.
    """
    arm = _robot(arm_urdf, source)
    gripper = _robot(gripper_urdf, gripper_source)
    for element in list(gripper):
        if (element.tag == "link" and element.get("name") == "world") or (
            element.tag == "joint" and _link(element, "parent") == "world"
        ):
            gripper.remove(element)
    arm_links = [link.get("name", "") for link in arm.findall("link")]
    if at_link not in arm_links or at_link == "world":
        choices = ", ".join(name for name in arm_links if name != "world")
        raise ModelSettingError(
            source,
            "end_effector.at_link",
            f"{at_link!r} is no link of the arm; its links: {choices}",
        )
    links = [link.get("name", "") for link in gripper.findall("link")]
    children = {_link(joint, "child") for joint in gripper.findall("joint")}
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise DescriptionError(
            f"{gripper_source}: {len(roots)} root links ({', '.join(roots) or 'none'}); a "
            "gripper's links form one tree, hung at the arm by its root"
        )
    mount = f"{at_link}_end_effector_joint"
    arm_names = set(arm_links) | {joint.get("name", "") for joint in arm.findall("joint")}
    gripper_names = [*links, *(joint.get("name", "") for joint in gripper.findall("joint")), mount]
    for name in gripper_names:
        if name in arm_names:
            raise ModelSettingError(
                source,
                "end_effector",
                f"{name!r} names a link or joint of both the arm and the gripper "
                f"({gripper_source}); rename one (e.g. with the gripper's prefix argument)",
            )
    materials = {material.get("name") for material in arm.findall("material")}
    for element in gripper:
        if element.tag == "material" and element.get("name") in materials:
            continue  # the arm defines it already; a second definition is an error to URDF
        arm.append(element)
    joint = ET.SubElement(arm, "joint", {"name": mount, "type": "fixed"})
    ET.SubElement(joint, "parent", {"link": at_link})
    ET.SubElement(joint, "child", {"link": roots[0]})
    ET.SubElement(joint, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})
    movable = tuple(
        joint.get("name", "") for joint in gripper.findall("joint") if joint.get("type") in MOVABLE
    )
    return ArmWithGripper(ET.tostring(arm, encoding="unicode"), movable, tuple(links))


def _robot(urdf: str, source: str) -> ET.Element:
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"{source} is not valid XML: {exc}") from None
    if robot.tag != "robot":
        raise DescriptionError(f"{source} has root <{robot.tag}>; a URDF's root is <robot>")
    return robot


def _link(joint: ET.Element, tag: str) -> str:
    found = joint.find(tag)
    return "" if found is None else found.get("link", "")
