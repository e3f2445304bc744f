"""``armfleet models``: the shipped arm models and one's own named models, with their
degrees of freedom and where each comes from."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from armfleet.cli.parser import OneLineParser
from armfleet.errors import ArmfleetError

if TYPE_CHECKING:  # types only; the model library and Pinocchio load in run()
    from armfleet.description import ModelLibrary


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser(
        "models",
        help="list the arm models (shipped and your own) and their DoF",
        description="List the shipped arm models and your own named models (the <name>.yaml "
        "settings files in $ARMFLEET_MODELS_PATH, else ~/.config/armfleet/models), with "
        "their degrees of freedom and where each comes from.",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print one line per model; a model of one's own that cannot be read is one line on
    stderr, and the exit code is then 2."""
    from armfleet.description import ModelLibrary

    library = ModelLibrary()
    shipped, own = library.names, library.own_models
    width = max((len(name) for name in (*shipped, *own.names)), default=5) + 1
    print(f"{'model':<{width}} {'dof':>3}  joints")
    for model in shipped:
        print(f"{model:<{width}} {_degrees_of_freedom(library, model)}")
    print(f"({len(shipped)} models in {library.folder})")
    problems = []
    for model in own.names:
        try:
            line = f"{model:<{width}} {_degrees_of_freedom(library, model)}"
        except ArmfleetError as exc:
            problems.append(str(exc))
            continue
        print(f"{line}  from {own.settings_file(model)}")
    print(f"({len(own.names)} of your own in {own.searched})")
    for problem in problems:
        print(f"armfleet: error: {problem}", file=sys.stderr)
    return 2 if problems else 0


def _degrees_of_freedom(library: ModelLibrary, model: str) -> str:
    """E.g. ``  9  7 arm + 2 other (fingers)``."""
    from armfleet.kinematics import ArmKinematics

    description = library.expand(model, "")
    kinematics = ArmKinematics(description.urdf, description.tool0)
    arm, other = len(kinematics.arm_indices), len(kinematics.auxiliary_indices)
    detail = f"{arm} arm" + (f" + {other} other (fingers)" if other else "")
    return f"{arm + other:>3}  {detail}"
