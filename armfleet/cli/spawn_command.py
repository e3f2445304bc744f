"""``armfleet spawn``: arms typed on the command line, brought up like a launch spec, in
a new world or, when one is running, in that one."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from armfleet.checks.model_reference import is_model_file
from armfleet.checks.names import ARM_NAME_PATTERN, check_arm_name
from armfleet.checks.number_ranges import ANGLE_DEG, WORLD_COORDINATE_M
from armfleet.cli.api_options import add_connect_arguments
from armfleet.cli.fleet_runner import run_fleet
from armfleet.cli.join_world import add_to_world, running_world
from armfleet.cli.misplaced_values import ValueTest
from armfleet.cli.parser import OneLineParser, UsageError
from armfleet.cli.run_options import add_run_arguments, check_run_arguments
from armfleet.description import ModelLibrary
from armfleet.description.model_options import options_from_keywords
from armfleet.errors import UnknownModel
from armfleet.frames.spawn_pose import AT_SYNTAX, SpawnPose
from armfleet.spec import ArmSpec, FleetSpec
from armfleet.spec.scene_rehearsal import rehearse


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "spawn",
        help="bring arms up one at a time in a new world and run it (or in the running one)",
        description="Bring arms up one at a time in one PyBullet world and run it "
        "until --duration or Ctrl-C. When a world is already running (see 'armfleet info'), "
        "the arms are added to it instead, unless --new-world.",
    )
    parser.add_argument("names", nargs="+", metavar="NAME", help="arm names, e.g. bob toby")
    parser.add_argument(
        "--at", nargs="+", metavar=AT_SYNTAX, required=True,
        help="spawn pose per name, in order [m, m, m, deg], e.g. --at 0,0 1,0,0,180",
    )  # fmt: skip
    parser.add_argument(
        "--model", nargs="+", default=["panda"], metavar="MODEL",
        help="one model for all arms or one per name: a shipped model (default: panda; see "
        "'armfleet models'), one of your own models by name, or your own .urdf/.urdf.xacro "
        "file or package:// URI",
    )  # fmt: skip
    parser.add_argument(
        "--xacro-arg", action="append", default=[], metavar="NAME=VALUE", type=_xacro_arg,
        help="an argument of the model files' xacro (repeatable), e.g. ur_type:=ur5e",
    )  # fmt: skip
    parser.add_argument(
        "--tool-link", metavar="LINK",
        help="the model file's link tool0 is put on (default: tool0, flange or tool_flange, "
        "else the end of the longest chain)",
    )  # fmt: skip
    parser.add_argument(
        "--end-effector", metavar="FILE",
        help="a gripper's .urdf/.urdf.xacro attached at the model file's tool link; its "
        "movable joints are the gripper's (home:, gripper_joints:, at_link: in a spec)",
    )  # fmt: skip
    add_run_arguments(parser)
    parser.add_argument(
        "--new-world", action="store_true",
        help="start a new world even if one is running",
    )  # fmt: skip
    add_connect_arguments(parser)
    parser.set_defaults(run=run)
    parser.help_ranges["at"] = f"X Y Z {WORLD_COORDINATE_M.valid}, YAW_DEG {ANGLE_DEG.valid}"
    # Names typed after --at or --model end up there: a value that is not a pose (has an
    # arm name's form) or not a model was meant as a name.
    parser.value_tests["--at"] = ValueTest("position", lambda text: not _is_name(text))
    parser.value_tests["--model"] = ValueTest(
        "model", lambda text: is_model_file(text) or text in ModelLibrary().available
    )


#: The flag of each model setting the command line takes.
_FLAGS = {"xacro_args": "--xacro-arg", "tool_link": "--tool-link", "end_effector": "--end-effector"}


def _xacro_arg(text: str) -> tuple[str, str]:
    """``NAME=VALUE`` (or ROS's ``NAME:=VALUE``) as a pair."""
    name, separator, value = text.replace(":=", "=", 1).partition("=")
    if not separator or not name.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is not NAME=VALUE (e.g. ur_type=ur5e)")
    return name.strip(), value


def _is_name(text: str) -> bool:
    return re.match(ARM_NAME_PATTERN, text) is not None


def spec_from_arguments(args: argparse.Namespace, models: ModelLibrary) -> FleetSpec:
    """The launch spec the arguments describe; raise UsageError or ArmfleetError."""
    names: list[str] = args.names
    counts_agree = len(args.at) == len(names) and len(args.model) in (1, len(names))
    if not counts_agree and args.misplaced_values is not None:
        raise UsageError(str(args.misplaced_values))
    if len(args.at) != len(names):
        raise UsageError(
            f"got {len(names)} names but {len(args.at)} --at poses; give one --at "
            f"{AT_SYNTAX} per name, in order"
        )
    if len(args.model) not in (1, len(names)):
        raise UsageError(
            f"got {len(args.model)} --model values for {len(names)} names; give one for all "
            "or one per name"
        )
    shipped, own = models.names, models.own_models.names
    chosen = args.model * len(names) if len(args.model) == 1 else args.model
    arms: list[ArmSpec] = []
    options = options_from_keywords(
        "command line",
        xacro_args=dict(getattr(args, "xacro_arg", [])) or None,
        tool_link=getattr(args, "tool_link", None),
        end_effector=getattr(args, "end_effector", None),
    )
    said = [_FLAGS[key] for key in options.given]
    if said and all(model in shipped for model in chosen):
        raise UsageError(
            f"{', '.join(said)}: settings of a model file (--model PATH) or of one of your "
            "own models; only shipped models were given"
        )
    for name, model, at in zip(names, chosen, args.at, strict=True):
        check_arm_name(name, [arm.name for arm in arms])
        if is_model_file(model):  # read by the world's process: an absolute path
            if not model.startswith("package://"):
                model = str(Path(model).expanduser().absolute())
            arms.append(ArmSpec(name, model, SpawnPose.parse(at), options=options))
            continue
        if model in shipped:
            arms.append(ArmSpec(name, model, SpawnPose.parse(at)))
        elif model in own:  # looked up by name in the world's process (docs/own-robot.md)
            arms.append(ArmSpec(name, model, SpawnPose.parse(at), options=options))
        else:
            raise UnknownModel(model, models.available)
    return FleetSpec(arms=tuple(arms), source="command line")


def run(args: argparse.Namespace) -> int:
    check_run_arguments(args)
    models = ModelLibrary()
    spec = spec_from_arguments(args, models)
    # The whole command-line fleet, as a spec is checked, before any world is asked:
    # no arm comes up when another of them would be refused.
    rehearse(spec, models)
    client = running_world(args)
    if client is None:
        return run_fleet(spec, args)
    with client:
        return add_to_world(client, spec, args.quiet)
