"""A robot of one's own: a URDF or xacro file (or ``package://`` URI), prefixed for you.

The file is expanded as its vendor meant (xacro with its arguments, ``$(find pkg)`` and
``package://`` resolved by :mod:`~armfleet.description.package_finder`), then armfleet
writes what the shipped models' wrapper files hold, so the rest of the library treats it
as one of them: every link and joint prefixed with the arm's name, the description's own
``world`` link and the joints hanging from it dropped (as are ``<ros2_control>``,
``<gazebo>`` and ``<transmission>``), a fixed ``world -> <name>_base_link`` joint carrying
the spawn pose, and the landmark frames ``<name>_base_link`` and ``<name>_tool0``.

What the description does not say is inferred by a stated rule:

- **base_link**: the root link (after ``world`` is dropped) if it is named ``base_link``;
  else a ``base_link`` frame is added on the root link.
- **tool0**: the first link named ``tool0``, ``flange`` or ``tool_flange`` (also with a
  prefix of the file's own, ``ur5e_tool0``), else the end of the longest chain of arm
  joints from the root (then of all joints), past no gripper joint; a ``tool0`` frame is
  added there unless it is ``tool0`` itself.
- **the gripper's joints**: movable joints with a ``<mimic>``, or named like fingers
  (``finger``, ``gripper``, ``jaw``, ``knuckle``); the arm's joints are the other movable
  joints from the root to tool0.
- **home**: every arm joint at zero, clamped into its limits.

Each can be given instead (``tool_link``, ``gripper_joints``, ``home``:
:class:`~armfleet.description.model_options.ModelOptions`), checked against the file. A
``tool0`` link of the file's own that is not the tool link is renamed ``file_tool0``.

A continuous joint is a revolute joint with no position limit (its ``<limit>`` gives only
its effort and velocity): :class:`~armfleet.kinematics.ArmKinematics` gives it infinite
limits, and its angle is never wrapped.
"""

from __future__ import annotations

import hashlib
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import xacro

from armfleet.checks.model_reference import DESCRIPTION_SUFFIXES
from armfleet.description.ament_index import ament_index
from armfleet.description.home_choice import HomeChoice
from armfleet.description.model_options import ModelOptions
from armfleet.description.package_finder import PackageFinder
from armfleet.errors import DescriptionError, ModelSettingError

#: Largest description file read [bytes]: a robot's URDF is kilobytes, a mesh is no URDF.
MAX_FILE_BYTES = 10_000_000
SUFFIXES = DESCRIPTION_SUFFIXES
#: Words in the name of a gripper's joint (with mimic joints: the gripper's joints).
FINGER_WORDS = ("finger", "gripper", "jaw", "knuckle")
#: Link names taken for the tool flange, in order.
TOOL_NAMES = ("tool0", "flange", "tool_flange")
#: Joint types that move (a continuous joint is a revolute joint with no position limit).
MOVABLE = ("revolute", "continuous", "prismatic")
REFUSED_JOINTS = ("floating", "planar")
_QUOTES = {'"': "&quot;"}
_URI_ATTRIBUTE = re.compile(r'filename="(?P<name>[^"]+)"')
#: How ament_index_python says a ``$(find pkg)`` found nothing.
_MISSING_PACKAGE = re.compile(r"package '([^']+)' not found")


@dataclass(frozen=True)
class ModelFile:
    """A description file and the xacro arguments it is expanded with (``options``: what
    the user says about it besides, for a wrapper written with them)."""

    path: Path
    xacro_args: tuple[tuple[str, str], ...] = ()
    options: ModelOptions | None = None

    @property
    def key(self) -> str:
        """A short name of the file, its arguments and options, for generated file names."""
        text = f"{self.path}|{self.xacro_args}"
        if self.options is not None and not self.options.is_default:
            text += f"|{self.options}"
        stem = re.sub(r"[^A-Za-z0-9_]", "_", self.path.name.split(".")[0])[:40] or "model"
        return f"{stem}_{hashlib.sha1(text.encode()).hexdigest()[:10]}"


def locate(model: str, finder: PackageFinder, base_dir: Path | None = None) -> Path:
    """The file ``model`` names: a path (relative to ``base_dir``, else the working folder)
    or ``package://pkg/path``.

    Raises:
        DescriptionError: it does not exist, is no file, or is not a URDF or xacro file.
        PackageNotFound: the package of a ``package://`` URI is nowhere.
    """
    if model.startswith("package://"):
        package, _, relative = model[len("package://") :].partition("/")
        path = finder.find(package) / relative
    else:
        path = Path(model).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
    where = "" if str(path.absolute()) == model else f" ({path.absolute()})"
    if not path.exists():
        raise DescriptionError(
            f"model file {model!r} not found{where}; give an existing .urdf or .urdf.xacro, "
            "or a shipped model (armfleet models)"
        )
    if not path.is_file():
        raise DescriptionError(f"model file {model!r} is not a file{where}")
    if not path.name.endswith(SUFFIXES):
        raise DescriptionError(
            f"model file {model!r} is neither .urdf nor .urdf.xacro/.xacro; give a robot "
            "description (shipped models: armfleet models)"
        )
    return path.resolve()


def expand_file(model: ModelFile, finder: PackageFinder) -> str:
    """The file's URDF: xacro run with its arguments (URIs still as written, except that
    plain relative mesh paths are made absolute).

    Raises:
        DescriptionError: too large, not UTF-8, not XML, an unknown xacro argument, or
            xacro failed (its message, with the file it names).
    """
    path = model.path
    if path.stat().st_size > MAX_FILE_BYTES:
        raise DescriptionError(
            f"{path}: {path.stat().st_size} bytes is too large for a robot description "
            f"(at most {MAX_FILE_BYTES}); is it a mesh?"
        )
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:  # unreadable: permissions, a folder's race, a broken disk
        raise DescriptionError(f"{path}: cannot read it ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise DescriptionError(
            f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})"
        ) from None
    if path.name.endswith(".xacro") or model.xacro_args:
        _check_arguments(path, text, dict(model.xacro_args))
        with ament_index(finder.packages()):
            try:
                document = xacro.process_file(str(path), mappings=dict(model.xacro_args))
            except Exception as exc:  # xacro raises bare Exceptions and XML errors
                problem = " ".join(str(exc).split())
                missing = _MISSING_PACKAGE.search(problem)
                if missing is not None:  # $(find pkg): every place searched, and the way out
                    finder.find(missing.group(1))
                raise DescriptionError(f"{path}: xacro failed: {problem}") from None
        text = document.toxml()
    return _absolute_mesh_paths(text, path.parent)


def _check_arguments(path: Path, text: str, given: Mapping[str, str]) -> None:
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise DescriptionError(f"{path} is not valid XML: {exc}") from None
    declared = {
        element.get("name", "")
        for element in root.iter()
        if element.tag in ("{http://www.ros.org/wiki/xacro}arg", "xacro:arg")
    }
    unknown = sorted(set(given) - declared)
    if unknown:
        raise DescriptionError(
            f"{path}: unknown xacro argument {', '.join(unknown)}; its arguments: "
            f"{', '.join(sorted(declared)) or 'none'}"
        )


def _absolute_mesh_paths(urdf: str, folder: Path) -> str:
    def absolute(match: re.Match[str]) -> str:
        name = match.group("name")
        if "://" in name or Path(name).is_absolute():
            return match.group(0)
        return f'filename="{(folder / name).resolve()}"'

    return _URI_ATTRIBUTE.sub(absolute, urdf)


@dataclass(frozen=True)
class Anatomy:
    """What armfleet reads off a description: its root, tool link, arm joints and home."""

    root: str
    tool: str
    arm_joints: tuple[str, ...]
    home: tuple[float, ...]
    #: The gripper's movable joints (mimic joints and finger-named ones), file order.
    gripper_joints: tuple[str, ...] = ()


def anatomy(
    urdf: str,
    source: str,
    tool_link: str | None = None,
    gripper_joints: Sequence[str] | None = None,
    home: Sequence[float] | None = None,
) -> Anatomy:
    """The root, tool link, arm chain and home of ``urdf`` (see the module docstring).

    ``tool_link``, ``gripper_joints`` and ``home``, when given, replace what the rule
    would infer (:class:`~armfleet.description.model_options.ModelOptions`): the arm's
    joints are then the movable joints from the root to that tool link, off the gripper.

    Raises:
        DescriptionError: not a ``<robot>``, a floating or planar joint, two roots, or no
            movable joint between the root and the tool.
        ModelSettingError: a given tool link that is no link of the file, a gripper joint
            that is no movable joint or is on the arm chain, a home of the wrong length or
            outside the limits (the valid choices named).
    """
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"{source} is not valid XML: {exc}") from None
    if robot.tag != "robot":
        raise DescriptionError(f"{source} has root <{robot.tag}>; a URDF's root is <robot>")
    joints = {}
    for joint in robot.findall("joint"):
        kind = joint.get("type", "")
        name = joint.get("name", "")
        if kind in REFUSED_JOINTS:
            raise DescriptionError(
                f"{source}: joint {name!r} is {kind}; an arm is fixed to the world (joints: "
                "revolute, continuous, prismatic, fixed)"
            )
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            raise DescriptionError(f"{source}: joint {name!r} lacks a parent or child link")
        joints[child.get("link", "")] = (name, kind, parent.get("link", ""), joint)
    links = [link.get("name", "") for link in robot.findall("link")]
    hung_from_world = {c for c, (_, _, p, _) in joints.items() if p == "world"}
    roots = [
        name
        for name in links
        if name != "world" and (name not in joints or name in hung_from_world)
    ]
    if len(roots) != 1:
        raise DescriptionError(
            f"{source}: {len(roots)} root links ({', '.join(roots) or 'none'}); an arm's "
            "links form one tree"
        )
    root = roots[0]

    def chain(link: str) -> list[tuple[str, str, ET.Element]]:
        out = []
        while link != root and link in joints:
            name, kind, parent, element = joints[link]
            out.append((name, kind, element))
            link = parent
        return out[::-1]

    movable = [j.get("name", "") for j in robot.findall("joint") if j.get("type") in MOVABLE]
    gripper = {
        name
        for name, kind, _, element in joints.values()
        if kind in MOVABLE and (element.find("mimic") is not None or _named_like_finger(name))
    }
    if gripper_joints is not None:
        gripper = set(gripper_joints)
        for wanted in gripper_joints:
            if wanted not in movable:
                raise ModelSettingError(
                    source,
                    "gripper_joints",
                    f"{wanted!r} is no movable joint of the file; its movable joints: "
                    f"{', '.join(movable) or 'none'}",
                )

    def reach(link: str) -> tuple[int, int]:
        """(arm joints, all joints) from the root to ``link``; (-1, -1) past a finger."""
        joints_above = chain(link)
        if any(name in gripper for name, _, _ in joints_above):
            return (-1, -1)
        return (sum(kind in MOVABLE for _, kind, _ in joints_above), len(joints_above))

    if tool_link is None:
        tool = _tool_link(links, root, reach)
    elif tool_link in links and tool_link != "world":
        tool = tool_link
    else:
        raise ModelSettingError(
            source,
            "tool_link",
            f"{tool_link!r} is no link of the file; its links: "
            f"{', '.join(n for n in links if n != 'world')}",
        )
    on_chain = [name for name, _, _ in chain(tool) if name in gripper]
    if gripper_joints is not None and on_chain:
        off_chain = [name for name in movable if name not in {n for n, _, _ in chain(tool)}]
        raise ModelSettingError(
            source,
            "gripper_joints",
            f"{on_chain[0]!r} is on the arm's chain from {root} to {tool}; gripper joints "
            f"are movable joints off it: {', '.join(off_chain) or 'none'}",
        )
    arm = [
        (name, element)
        for name, kind, element in chain(tool)
        if kind in MOVABLE and name not in gripper
    ]
    if not arm:
        raise DescriptionError(
            f"{source}: no movable joint between {root} and {tool}; an arm moves"
        )
    return Anatomy(
        root,
        tool,
        tuple(n for n, _ in arm),
        tuple(_zero_within(e) for _, e in arm) if home is None else _given_home(source, arm, home),
        tuple(j.get("name", "") for j in robot.findall("joint") if j.get("name") in gripper),
    )


def _tool_link(links: list[str], root: str, reach: Callable[[str], tuple[int, int]]) -> str:
    for wanted in TOOL_NAMES:
        for name in links:
            if name == wanted or name.endswith("_" + wanted):
                return name
    # The end of the longest chain of arm joints, then of all joints (the first on a tie).
    candidates = [name for name in links if name not in ("world", root)]
    return max(candidates, key=reach, default=root)


def _given_home(
    source: str, arm: list[tuple[str, ET.Element]], home: Sequence[float]
) -> tuple[float, ...]:
    names = [name for name, _ in arm]
    if len(home) != len(arm):
        raise ModelSettingError(
            source,
            "home",
            f"{len(home)} values for {len(arm)} arm joints; give one per joint: {', '.join(names)}",
        )
    for (name, joint), value in zip(arm, home, strict=True):
        lower, upper = _position_limits(joint)
        if not lower <= value <= upper:
            raise ModelSettingError(
                source, "home", f"{name} = {value:g} is outside its limits [{lower:g}, {upper:g}]"
            )
    return tuple(float(value) for value in home)


def _position_limits(joint: ET.Element) -> tuple[float, float]:
    """(lower, upper) of a movable joint [rad or m]; unbounded for a continuous one."""
    limit = joint.find("limit")
    if limit is None or joint.get("type") == "continuous":
        return -math.inf, math.inf
    return float(limit.get("lower", "0") or 0), float(limit.get("upper", "0") or 0)


def _named_like_finger(joint: str) -> bool:
    return any(word in joint.lower() for word in FINGER_WORDS)


def _zero_within(joint: ET.Element) -> float:
    limit = joint.find("limit")
    if limit is None or joint.get("type") == "continuous":  # its limit's bounds mean nothing
        return 0.0
    lower = float(limit.get("lower", "0") or 0)
    upper = float(limit.get("upper", "0") or 0)
    return min(max(0.0, lower), upper) if lower <= upper else 0.0


def wrapper_xacro(
    name: str, upstream: Path, found: Anatomy, home_choice: HomeChoice | None = None
) -> str:
    """The wrapper armfleet writes for a description file (as ``description/`` holds for
    the shipped models): the world anchor, base_link and tool0 around the prefixed file,
    and which home it has (``home_choice``)."""
    home = " ".join(repr(value) for value in found.home)
    chosen = "" if home_choice is None else home_choice.text
    gripper = " ".join(found.gripper_joints)
    base = "" if found.root == "base_link" else _landmark("base_link", "base_link", found.root)
    tool = "" if found.tool == "tool0" else _landmark("tool0", found.tool, "tool0")
    return f"""<?xml version="1.0"?>
<!-- Written by armfleet for {upstream.name}: the arm's own description, prefixed. -->
<robot name="{name}" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="armfleet_upstream_urdf" value="file://{upstream}"/>
  <xacro:property name="armfleet_home" value="{home}"/>
  <xacro:property name="armfleet_gripper_joints" value="{gripper}"/>
  <xacro:property name="armfleet_home_choice" value="{escape(chosen, _QUOTES)}"/>
  <xacro:arg name="prefix" default=""/>
  <xacro:arg name="xyz" default="0 0 0"/>
  <xacro:arg name="rpy" default="0 0 0"/>
  <xacro:arg name="upstream_macro" default=""/>
  <xacro:property name="prefix" value="$(arg prefix)"/>
  <xacro:include filename="$(arg upstream_macro)"/>
  <link name="world"/>
  <joint name="${{prefix}}world_joint" type="fixed">
    <parent link="world"/>
    <child link="${{prefix}}base_link"/>
    <origin xyz="$(arg xyz)" rpy="$(arg rpy)"/>
  </joint>{base}
  <xacro:upstream prefix="${{prefix}}"/>{tool}
</robot>
"""


#: The name a file's own ``tool0`` link gets when another link is the tool link (the
#: landmark ``tool0`` is then armfleet's, on that link).
FILE_TOOL0 = "file_tool0"


def free_tool0(urdf: str, found: Anatomy) -> str:
    """``urdf`` with its own ``tool0`` link renamed :data:`FILE_TOOL0` if the tool link is
    another (a given ``tool_link``), so that the landmark ``tool0`` can go there."""
    if found.tool == "tool0":
        return urdf
    robot = ET.fromstring(urdf)
    renamed = False
    for link in robot.iter("link"):
        if link.get("name") == "tool0":
            link.set("name", FILE_TOOL0)
            renamed = True
    if not renamed:
        return urdf
    for joint in robot.iter("joint"):
        for end in (joint.find("parent"), joint.find("child")):
            if end is not None and end.get("link") == "tool0":
                end.set("link", FILE_TOOL0)
    return ET.tostring(robot, encoding="unicode")


def _landmark(frame: str, parent: str, child: str) -> str:
    """The landmark link ``frame`` and the fixed joint joining ``parent`` to ``child``."""
    return f"""
  <link name="${{prefix}}{frame}"/>
  <joint name="${{prefix}}{frame}_joint" type="fixed">
    <parent link="${{prefix}}{parent}"/>
    <child link="${{prefix}}{child}"/>
  </joint>"""
