"""What in a robot description cannot be simulated, one line each, naming the link, joint
or file: found before the arm is built, so a bad file is refused with the world untouched
(:meth:`ModelLibrary.expand`) and listed whole by ``armfleet check-model``.

The rules, and what PyBullet and Pinocchio do without them (measured, PyBullet 3.2 and
Pinocchio 4.1):

- **A moving link has mass.** Every movable joint must move some mass: its child link
  and the links below it (through any joint) weigh more than zero. A massless child is
  fine when links below it have mass (a massless ``*_link8`` before a hand); a massless
  frame on a fixed joint (``tool0``, ``flange``) is fine as it moves nothing. Without
  mass below it PyBullet holds the joint still whatever torque it is given, and
  Pinocchio's joint-space inertia has a zero row (its forward dynamics return NaN).
  A link without ``<inertial>`` has no mass (URDF's meaning; PyBullet alone would give
  it 1 kg, which armfleet does not let it do).
- **Every movable joint drives some inertia** about its axis, with the joints below it
  free: the pivots of Pinocchio's factorisation of the joint-space inertia at the zero
  configuration (its articulated inertias) exceed :data:`MIN_JOINT_INERTIA_KG_M2`. This
  also catches a mass sitting on the joint's axis with no inertia, and a massless link
  between two joints about the same axis; PyBullet holds such a joint still too.
- **An inertia tensor is physical**: mass and the six components finite, mass not
  negative, the tensor positive semi-definite, within :data:`INERTIA_TOLERANCE` of its
  largest principal moment (vendors' files round to a few digits). Its principal moments
  should also obey the triangle inequality (each at most the sum of the other two); many
  published descriptions break it (example-robot-data's Allegro hand, ANYmal's cameras,
  PR2's sensor mounts) and PyBullet and Pinocchio simulate them all the same, so that one
  is reported (``armfleet check-model``, a warning at load) but not refused.
- **A mesh is there and readable** after ``package://`` and ``file://`` resolution
  (:mod:`~armfleet.description.mesh_readability` says what PyBullet reads).

An include cycle (and a ``$(find)`` cycle) is found while xacro runs:
:mod:`~armfleet.description.include_cycle`.
"""

from __future__ import annotations

import enum
import logging
import math
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from armfleet.description.mesh_readability import mesh_problem
from armfleet.description.resource_resolver import ResourceResolver
from armfleet.errors import DescriptionError, ResourceNotFound

MOVABLE_JOINTS = ("revolute", "prismatic", "continuous")
#: Least inertia a movable joint drives about its axis [kg m^2]: floating-point zero for a
#: robot arm (a 1 g finger at 1 cm from its axis is 1e-7 kg m^2).
MIN_JOINT_INERTIA_KG_M2 = 1e-12
#: How far an inertia tensor may break positive semi-definiteness or the triangle
#: inequality, relative to its largest principal moment (rounding in vendors' files).
INERTIA_TOLERANCE = 1e-3
_INERTIA_COMPONENTS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_log = logging.getLogger("armfleet")


class ProblemKind(enum.Enum):
    """What is wrong with a description."""

    MASSLESS_MOVING_LINK = "massless moving link"
    NO_JOINT_INERTIA = "joint without inertia"
    INVALID_INERTIA = "invalid inertia"
    MESH_NOT_FOUND = "mesh not found"
    MESH_UNREADABLE = "mesh unreadable"
    INCLUDE_CYCLE = "include cycle"


@dataclass(frozen=True)
class ModelProblem:
    """One problem of a description.

    Attributes:
        kind: what kind of problem.
        subject: the link, joint or file it is about.
        text: one line saying it, naming ``subject``.
        fatal: the description cannot be simulated with it (refused at load); else it
            is only reported.
    """

    kind: ProblemKind
    subject: str
    text: str
    fatal: bool = True


def model_problems(urdf: str, resolver: ResourceResolver) -> list[ModelProblem]:
    """The problems of ``urdf`` (a description as xacro expanded it, URIs as written),
    in file order: inertias and masses first, then meshes.

    Raises:
        DescriptionError: ``urdf`` is not XML.
    """
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise DescriptionError(f"not valid XML: {exc}") from None
    problems = list(_inertia_problems(robot))
    problems += _massless_moving_links(robot)
    if not problems:  # Pinocchio's dynamics are meaningful only with valid masses
        problems += _joints_without_inertia(urdf)
    problems += _mesh_problems(robot, resolver)
    return problems


def refuse_problems(urdf: str, source: str, resolver: ResourceResolver) -> None:
    """Raise if ``urdf`` (expanded from ``source``) has a fatal problem; log the others
    as warnings on the ``armfleet`` logger.

    Raises:
        DescriptionError: one line: the first fatal problem, and how many more there are.
    """
    problems = model_problems(urdf, resolver)
    fatal = [problem for problem in problems if problem.fatal]
    if fatal:
        more = len(fatal) - 1
        rest = f" (and {more} more: armfleet check-model {source})" if more else ""
        raise DescriptionError(f"{source}: {fatal[0].text}{rest}")
    for problem in problems:
        _log.warning("%s: %s", source, problem.text)


def _inertia_problems(robot: ET.Element) -> Iterator[ModelProblem]:
    for link in robot.findall("link"):
        name = link.get("name", "")
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass_element = inertial.find("mass")
        mass = _number(mass_element.get("value") if mass_element is not None else "0")
        if mass is None or not math.isfinite(mass) or mass < 0.0:
            shown = mass_element.get("value") if mass_element is not None else None
            yield _invalid(name, f"has mass {shown!r} kg; a mass is a finite number >= 0")
            continue
        element = inertial.find("inertia")
        if element is None:
            continue
        values = [_number(element.get(c, "0")) for c in _INERTIA_COMPONENTS]
        if any(v is None or not math.isfinite(v) for v in values):
            shown = ", ".join(f"{c}={element.get(c)}" for c in _INERTIA_COMPONENTS)
            yield _invalid(name, f"has an inertia that is not finite numbers ({shown})")
            continue
        problem = _tensor_problem([float(v or 0.0) for v in values])
        if problem is not None:
            yield _invalid(name, *problem)


def _tensor_problem(values: list[float]) -> tuple[str, bool] | None:
    """What is wrong with the tensor, and whether it is fatal, or None."""
    ixx, ixy, ixz, iyy, iyz, izz = values
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    moments = np.linalg.eigvalsh(tensor)  # ascending
    tolerance = INERTIA_TOLERANCE * max(abs(float(moments[-1])), 0.0)
    shown = ", ".join(f"{m:.4g}" for m in moments)
    if moments[0] < -tolerance or (moments[-1] <= 0.0 and np.any(tensor != 0.0)):
        return (
            f"has an inertia tensor that is not positive (principal moments {shown} kg m^2)",
            True,
        )
    if moments[0] + moments[1] < moments[2] - tolerance:
        return (
            f"has an inertia tensor breaking the triangle inequality (principal moments "
            f"{shown} kg m^2: the largest exceeds the sum of the others)"
        ), False
    return None


def _invalid(link: str, problem: str, fatal: bool = True) -> ModelProblem:
    return ModelProblem(ProblemKind.INVALID_INERTIA, link, f"link {link!r} {problem}", fatal)


def _massless_moving_links(robot: ET.Element) -> list[ModelProblem]:
    """The topmost child link of each movable joint with no mass at or below it."""
    masses = {link.get("name", ""): _link_mass(link) for link in robot.findall("link")}
    below: dict[str, list[tuple[str, str, str]]] = {}
    parents = set()
    for joint in robot.findall("joint"):
        parent_element, child_element = joint.find("parent"), joint.find("child")
        if parent_element is None or child_element is None:
            continue
        parent_link = parent_element.get("link", "")
        child_link = child_element.get("link", "")
        below.setdefault(parent_link, []).append(
            (joint.get("name", ""), joint.get("type", ""), child_link)
        )
        parents.add(child_link)

    def subtree_mass(link: str) -> float:
        return masses.get(link, 0.0) + sum(subtree_mass(c) for _, _, c in below.get(link, ()))

    problems = []
    pending = [name for name in masses if name not in parents]
    while pending:
        link = pending.pop()
        for joint_name, kind, child in below.get(link, ()):
            if kind in MOVABLE_JOINTS and subtree_mass(child) <= 0.0:
                problems.append(
                    ModelProblem(
                        ProblemKind.MASSLESS_MOVING_LINK,
                        child,
                        f"link {child!r} is moved by {kind} joint {joint_name!r} but neither "
                        "it nor any link below it has mass; give it an <inertial> with a mass > 0",
                    )
                )
            else:
                pending.append(child)
    return problems


def _link_mass(link: ET.Element) -> float:
    mass = link.find("inertial/mass")
    value = _number(mass.get("value", "0")) if mass is not None else 0.0
    return value if value is not None and math.isfinite(value) and value > 0.0 else 0.0


def _joints_without_inertia(urdf: str) -> list[ModelProblem]:
    """Movable joints whose articulated inertia about their axis is (numerically) zero."""
    try:
        model = pin.buildModelFromXML(urdf)
    except Exception:  # Pinocchio's own parse errors come up when the arm is built
        return []
    data = model.createData()
    pin.crba(model, data, pin.neutral(model))
    pin.cholesky.decompose(model, data)
    problems = []
    for joint_id in range(1, model.njoints):
        joint = model.joints[joint_id]
        pivots = data.D[joint.idx_v : joint.idx_v + joint.nv]
        if joint.nv and float(np.min(pivots)) <= MIN_JOINT_INERTIA_KG_M2:
            name = model.names[joint_id]
            problems.append(
                ModelProblem(
                    ProblemKind.NO_JOINT_INERTIA,
                    name,
                    f"joint {name!r} drives no inertia about its axis (its links' masses lie "
                    "on the axis with no inertia, or a massless link sits between it and a "
                    "joint about the same axis); PyBullet would hold it still",
                )
            )
    return problems


def _mesh_problems(robot: ET.Element, resolver: ResourceResolver) -> Iterator[ModelProblem]:
    seen: dict[tuple[str, bool], str | None] = {}
    for link in robot.findall("link"):
        name = link.get("name", "")
        for role in ("visual", "collision"):
            for mesh in link.findall(f"{role}/geometry/mesh"):
                uri = mesh.get("filename", "")
                key = (uri, role == "collision")
                if key not in seen:
                    seen[key] = _file_problem(uri, resolver, role == "collision")
                problem = seen[key]
                if problem is None:
                    continue
                kind = (
                    ProblemKind.MESH_NOT_FOUND
                    if problem.startswith("not found")
                    else ProblemKind.MESH_UNREADABLE
                )
                yield ModelProblem(kind, name, f"link {name!r}: {role} mesh {uri!r} {problem}")


def _file_problem(uri: str, resolver: ResourceResolver, collision: bool) -> str | None:
    try:
        path = resolver.resolve(uri)
    except ResourceNotFound as missing:
        searched = ", ".join(missing.searched) or "nowhere to search"
        return f"not found (searched: {searched})"
    return mesh_problem(Path(path), collision)


def _number(text: str | None) -> float | None:
    try:
        return float(text) if text is not None else None
    except ValueError:
        return None
