"""Turn an upstream URDF (e.g. from example-robot-data) into a prefixable xacro macro.

Upstream URDFs name their links ``panda_link1``; an arm in a shared world
needs ``bob_panda_link1``. Instead of copying their numbers into our files,
the description xacro includes the upstream file as a macro whose every link
and joint name (and every reference to one) is ``${prefix}`` + the upstream
name. Meshes, inertias and limits stay those of the installed upstream file.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from armfleet.errors import DescriptionError

XACRO_NS = "http://www.ros.org/wiki/xacro"
#: Upstream elements that only matter to ROS tooling and name joints themselves.
_DROPPED_TAGS = ("transmission", "gazebo", "ros2_control")


def prefixable_macro(urdf_text: str, macro_name: str, source: str) -> str:
    """Return xacro text defining ``<xacro:macro name=macro_name params="prefix">``.

    The upstream ``world`` link and the joints hanging it (the description adds
    its own world anchor) are dropped, as are ROS-only elements.

    Args:
        urdf_text: the upstream URDF.
        macro_name: name of the generated macro.
        source: where the text came from, for error messages.
    """
    try:
        robot = ET.fromstring(urdf_text)
    except ET.ParseError as exc:
        raise DescriptionError(f"upstream URDF {source} is not valid XML: {exc}") from exc
    if robot.tag != "robot":
        raise DescriptionError(f"upstream URDF {source} has root <{robot.tag}>, expected <robot>")

    for element in list(robot):
        if (
            element.tag in _DROPPED_TAGS
            or (element.tag == "link" and element.get("name") == "world")
            or (element.tag == "joint" and _attr(element, "parent", "link") == "world")
        ):
            robot.remove(element)

    def prefixed(name: str | None) -> str:
        if not name:
            raise DescriptionError(f"upstream URDF {source} has an element without a name")
        return "${prefix}" + name

    for link in robot.iter("link"):
        link.set("name", prefixed(link.get("name")))
    for joint in robot.iter("joint"):
        joint.set("name", prefixed(joint.get("name")))
        for tag in ("parent", "child"):
            ref = joint.find(tag)
            if ref is not None:
                ref.set("link", prefixed(ref.get("link")))
        mimic = joint.find("mimic")
        if mimic is not None:
            mimic.set("joint", prefixed(mimic.get("joint")))

    ET.register_namespace("xacro", XACRO_NS)
    wrapper = ET.Element("robot")
    macro = ET.SubElement(wrapper, f"{{{XACRO_NS}}}macro", {"name": macro_name, "params": "prefix"})
    macro.extend(list(robot))
    return ET.tostring(wrapper, encoding="unicode")


def _attr(element: ET.Element, child: str, attribute: str) -> str | None:
    found = element.find(child)
    return None if found is None else found.get(attribute)
