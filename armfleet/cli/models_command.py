"""``armfleet models``: the arm models in ``description/`` and their degrees of freedom."""

from __future__ import annotations

import argparse

from armfleet.cli.parser import OneLineParser
from armfleet.description import ModelLibrary
from armfleet.kinematics import ArmKinematics


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = subparsers.add_parser("models", help="list the arm models and their DoF")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    library = ModelLibrary()
    print(f"{'model':<10} {'dof':>3}  joints")
    for model in library.names:
        description = library.expand(model, "")
        kinematics = ArmKinematics(description.urdf, description.tool0)
        arm, other = len(kinematics.arm_indices), len(kinematics.auxiliary_indices)
        detail = f"{arm} arm" + (f" + {other} other (fingers)" if other else "")
        print(f"{model:<10} {arm + other:>3}  {detail}")
    print(f"({len(library.names)} models in {library.folder})")
    return 0
