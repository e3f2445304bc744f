"""``armfleet check-model FILE``: what armfleet makes of a robot description, and its problems.

The file is expanded as ``spawn --model FILE`` would (xacro arguments, packages), read
(joints, arm, tool, gripper, masses), checked (:mod:`~armfleet.description.model_problems`)
and, if nothing fatal was found, spawned in a scratch headless world: its home and how it
was chosen, the self-contact pairs ignored, and a test move (every arm joint
:data:`MOVE_RAD` from home and back, the error to the commanded target measured once the
reference has stopped and the arm has settled for :data:`SETTLE_S`). Exit 0 when there is
no problem, else 2 with one line per problem on stderr.
"""

from __future__ import annotations

import argparse
import logging
import sys
import xml.etree.ElementTree as ET
from collections.abc import Sequence

import numpy as np

from armfleet.arms.arm import Arm
from armfleet.cli.parser import OneLineParser
from armfleet.cli.path_arguments import path_text
from armfleet.cli.run_options import use_package_paths
from armfleet.cli.spawn_command import _xacro_arg
from armfleet.description import ModelLibrary
from armfleet.description.file_model import Anatomy, ModelFile, anatomy, expand_file, locate
from armfleet.description.include_cycle import naming_include_cycle
from armfleet.description.model_problems import model_problems
from armfleet.errors import ArmfleetError
from armfleet.messages import FloatArray
from armfleet.world import World

#: The test move: every arm joint this far from home, then back [rad or m].
MOVE_RAD = 0.15
#: The arm tracks if every arm joint ends within this of the target [rad or m]
#: (tests/test_own_robot.py's criterion).
TRACKING_RAD = 1e-3
#: Time the arm settles once its reference has stopped, before the error is read [s].
SETTLE_S = 0.2
#: Longest a leg of the test move may take before it counts as not arriving [s].
MOVE_TIMEOUT_S = 30.0
#: The arm's name in the scratch world (its prefix is taken off what is printed).
ARM = "check"
_UNITS = {"prismatic": "m"}


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "check-model",
        help="check a URDF/xacro file: joints, tool, gripper, home, masses, problems, tracking",
        description="Load a robot description in a scratch headless world and print what "
        "armfleet found in it; exit 2 with one line per problem on stderr.",
    )
    parser.add_argument(
        "file", type=path_text, metavar="FILE",
        help="a .urdf or .urdf.xacro file, or a package:// URI",
    )  # fmt: skip
    parser.add_argument(
        "--xacro-arg", action="append", default=[], metavar="NAME=VALUE", type=_xacro_arg,
        help="an argument of the file's xacro (repeatable), e.g. ur_type:=ur5e",
    )  # fmt: skip
    parser.add_argument(
        "--package-path", action="append", default=[], metavar="DIR", type=path_text,
        help="a folder of ROS packages (or a package) for package:// and $(find) (repeatable)",
    )  # fmt: skip
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    use_package_paths(args.package_path)
    library = ModelLibrary()
    xacro_args = dict(args.xacro_arg)
    path = locate(args.file, library.finder)  # a missing file is the command's error
    print(f"model file: {path}")
    if xacro_args:
        print(f"xacro arguments: {', '.join(f'{k}={v}' for k, v in xacro_args.items())}")
    problems: list[str] = []
    try:
        with naming_include_cycle(path):
            urdf = expand_file(ModelFile(path, tuple(sorted(xacro_args.items()))), library.finder)
    except ArmfleetError as exc:
        return _report([str(exc)])
    found = model_problems(urdf, library.resolver)
    problems += [problem.text + ("" if problem.fatal else " (reported, not refused)")
                 for problem in found]  # fmt: skip
    robot = ET.fromstring(urdf)
    try:
        parts: Anatomy | None = anatomy(urdf, str(path))
    except ArmfleetError as exc:
        parts, problems = None, [*problems, str(exc)]
    _print_joints(robot, parts)
    _print_masses(robot)
    if parts is not None and not any(problem.fatal for problem in found):
        logging.getLogger("armfleet").setLevel(logging.ERROR)  # its problems are listed here
        try:
            problems += _spawn_and_move(args.file, xacro_args)
        except ArmfleetError as exc:
            problems.append(str(exc))
    return _report(problems)


def _print_joints(robot: ET.Element, parts: Anatomy | None) -> None:
    arm = parts.arm_joints if parts else ()
    gripper = parts.gripper_joints if parts else ()
    joints = robot.findall("joint")
    width = max((len(j.get("name", "")) for j in joints), default=0)
    print(f"joints ({len(joints)}):")
    for joint in joints:
        name, kind = joint.get("name", ""), joint.get("type", "")
        limit = joint.find("limit")
        if kind == "fixed":
            bounds = ""
        elif kind == "continuous" or limit is None:
            bounds = "unbounded"
        else:
            unit = _UNITS.get(kind, "rad")
            bounds = f"[{float(limit.get('lower', 0)):g}, {float(limit.get('upper', 0)):g}] {unit}"
        mimic = joint.find("mimic")
        role = "arm" if name in arm else "gripper" if name in gripper else ""
        if mimic is not None:
            role = f"{role} mimics {mimic.get('joint')}".strip()
        print(f"  {name:<{width}}  {kind:<10} {bounds:<28} {role}".rstrip())
    if parts is not None:
        print(f"arm joints: {', '.join(parts.arm_joints)}")
        print(f"root link: {parts.root}; tool link: {parts.tool}")
        print(f"gripper joints: {', '.join(parts.gripper_joints) or 'none'}")


def _print_masses(robot: ET.Element) -> None:
    masses = []
    for link in robot.findall("link"):
        element = link.find("inertial/mass")
        try:
            mass = float(element.get("value", "0")) if element is not None else 0.0
        except ValueError:
            mass = float("nan")
        masses.append((link.get("name", ""), mass))
    heavy = [f"{name} {mass:.4g}" for name, mass in masses if mass != 0.0]
    massless = [name for name, mass in masses if mass == 0.0]
    total = sum(mass for _, mass in masses)
    print(f"mass: {total:.4g} kg in {len(heavy)} links ({', '.join(heavy)})")
    if massless:
        print(f"massless links: {', '.join(massless)}")


def _spawn_and_move(model: str, xacro_args: dict[str, str]) -> list[str]:
    """Spawn the file in a scratch world, print its home, contacts and test move; return
    the problems found."""
    prefix = f"{ARM}_"
    with World() as world:
        arm = world.spawn(ARM, model=model, at=(0.0, 0.0), xacro_args=xacro_args)
        description = arm.description
        names = [name.removeprefix(prefix) for name in arm.joint_names]
        home = np.asarray(description.home, dtype=float)
        choice = description.home_choice.clause if description.home_choice else "home"
        print(f"home: {_values(names, home)}  ({choice.removeprefix('home: ')})")
        pairs = [(a.removeprefix(prefix), b.removeprefix(prefix))
                 for a, b in description.ignored_contacts]  # fmt: skip
        shown = ", ".join(f"{a}/{b}" for a, b in pairs)
        print(f"self-contact pairs ignored ({len(pairs)}, never touching when sampled): "
              f"{shown or 'none'}")  # fmt: skip
        _, upper = arm.joint_limits
        away = np.where(home + MOVE_RAD <= upper, home + MOVE_RAD, home - MOVE_RAD)
        errors = [_settle(world, arm, away), _settle(world, arm, home)]
    worst = max(errors, key=lambda error: error[0])
    joint = names[worst[1]]
    verdict = "tracks" if worst[0] < TRACKING_RAD else "does NOT track"
    print(f"test move: every arm joint {MOVE_RAD} from home and back: largest error "
          f"{worst[0]:.2e} ({joint}), {verdict} (< {TRACKING_RAD:g})")  # fmt: skip
    if worst[0] < TRACKING_RAD:
        return []
    return [
        f"joint {joint!r} does not track a {MOVE_RAD} rad move: {worst[0]:.3g} from its "
        f"target after settling (at most {TRACKING_RAD:g}); check its masses and limits"
    ]


def _settle(world: World, arm: Arm, target: FloatArray) -> tuple[float, int]:
    """Move to ``target``, settle, and return the largest error and its joint's index."""
    arm.move_to(target)
    waited = 0.0
    while arm.is_moving and waited < MOVE_TIMEOUT_S:
        world.run(0.1)
        waited += 0.1
    world.run(SETTLE_S)
    error = np.abs(arm.positions - target)
    return float(error.max()), int(np.argmax(error))


def _values(names: Sequence[str], values: FloatArray) -> str:
    return ", ".join(f"{name}={value:.4g}" for name, value in zip(names, values, strict=True))


def _report(problems: list[str]) -> int:
    print(f"problems: {len(problems) or 'none'}")
    for problem in problems:
        print(f"armfleet: problem: {problem}", file=sys.stderr)
    return 2 if problems else 0
