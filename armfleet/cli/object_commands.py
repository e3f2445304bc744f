"""``armfleet objects``, ``add-object`` and ``remove-object``: the running world's scene objects."""

from __future__ import annotations

import argparse

from armfleet.checks.number_ranges import ANGLE_DEG, WORLD_COORDINATE_M
from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.parser import OneLineParser
from armfleet.objects.object_spec import (
    DEFAULT_MASS_KG,
    MAX_MASS_KG,
    MAX_SIZE_M,
    SIZE_MEANING,
    Shape,
)
from armfleet.remote.world_info import ObjectInfo

#: Shapes a client may add: armfleet.services.object_services.REMOTE_SHAPES, derived here
#: by the same rule so that these commands start without the planner that module loads
#: (tests/test_cli_startup.py checks the two agree).
REMOTE_SHAPES = tuple(s.value for s in Shape if s is not Shape.MESH)


def add_parsers(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    add_remote_command(
        subparsers, "objects", "list the scene objects of the running world"
    ).set_defaults(run=list_objects)
    add = add_remote_command(subparsers, "add-object", "add a scene object to the running world")
    add.add_argument("name", metavar="NAME", help="object name, unique among arms and objects")
    add.add_argument("shape", choices=REMOTE_SHAPES, help="its shape")
    sizes = "; ".join(f"{shape.value} {meaning}" for shape, meaning in SIZE_MEANING.items())
    add.add_argument(
        "--size", nargs="+", type=float, required=True, metavar="M",
        help=f"size [m]: {sizes}",
    )  # fmt: skip
    add.add_argument(
        "--mass", type=float, default=DEFAULT_MASS_KG, metavar="KG",
        help=f"mass [kg] (default {DEFAULT_MASS_KG:g}); 0: static, fixed like a table",
    )  # fmt: skip
    add.add_argument(
        "--at", nargs=3, type=float, default=[0.0, 0.0, 0.0], metavar=("X", "Y", "Z"),
        help="position of its centre in the world [m] (default 0 0 0)",
    )  # fmt: skip
    add.add_argument(
        "--yaw", type=float, default=0.0, metavar="DEG",
        help="rotation about the world's z [deg] (default 0)",
    )  # fmt: skip
    add.set_defaults(run=add_object)
    add.help_ranges.update(
        size=f"metres, each in (0, {MAX_SIZE_M:g}]",
        mass=f"kg in [0, {MAX_MASS_KG:g}]",
        at=WORLD_COORDINATE_M.valid,
        yaw=ANGLE_DEG.valid,
    )
    remove = add_remote_command(
        subparsers, "remove-object", "take scene objects out of the running world"
    )
    remove.add_argument("names", nargs="+", metavar="NAME", help="object names")
    remove.set_defaults(run=remove_objects)


def list_objects(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        objects = client.objects
        info = client.info()
    print(f"{'name':<12} {'shape':<9} {'mass [kg]':<10} {'at (x, y, z [m])':<26} size [m]")
    for obj in objects.values():
        print(describe(obj))
    print(f"({len(objects)} object(s); t={info.time_s:.3f}s, {client.address})")
    return 0


def describe(obj: ObjectInfo) -> str:
    mass = "static" if obj.static else f"{obj.mass:g}"
    at = ", ".join(f"{v:+.3f}" for v in obj.position)
    size = " ".join(f"{v:g}" for v in obj.size)
    return f"{obj.name:<12} {obj.shape:<9} {mass:<10} {at:<26} {size}"


def add_object(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        obj = client.add_object(
            args.name,
            args.shape,
            size=args.size,
            mass=args.mass,
            at=args.at,
            rpy_deg=(0.0, 0.0, args.yaw),
        )
    kind = "static" if obj.static else f"{obj.mass:g} kg"
    at = ", ".join(f"{v:.3f}" for v in obj.position)
    print(f"{obj.name}: added, {obj.shape} ({kind}) at ({at}) m")
    return 0


def remove_objects(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        for name in args.names:
            client.remove_object(name)
            print(f"{name}: removed")
    return 0
