"""``--avoid-collisions [--clearance M] [--planning-timeout S | --budget N]`` of ``move``
and ``move-together``: plan the motion around everything in the world, within a time or
within N planner iterations (the same path every time, on any machine, under any load).

The numbers are checked while the arguments are parsed, against the ranges the
planner and the live API check (:data:`~armfleet.checks.number_ranges.CLEARANCE_M`,
:data:`~armfleet.checks.number_ranges.PLANNING_TIMEOUT_S`,
:data:`~armfleet.checks.number_ranges.PLANNING_BUDGET`), so a bad one is refused
before anything is sent. A plan that fails is the world's one line (``cannot plan bob:
goal in collision: ...``), exit code 2, and nothing moved.
"""

from __future__ import annotations

import argparse
from typing import Any

from armfleet.checks.number_ranges import CLEARANCE_M, PLANNING_BUDGET, PLANNING_TIMEOUT_S
from armfleet.cli.number_arguments import number_in
from armfleet.cli.parser import UsageError
from armfleet.motion.move_options import DEFAULT_CLEARANCE_M, DEFAULT_TIMEOUT_S

#: Options that only mean something with ``--avoid-collisions``, by ``dest``.
_PLANNING_ONLY = {
    "clearance": "--clearance",
    "planning_timeout": "--planning-timeout",
    "budget": "--budget",
}


def add_planning_arguments(
    parser: argparse.ArgumentParser,
    flag_group: argparse._ActionsContainer | None = None,
    what: str = "the arm",
) -> None:
    """Add the options to ``parser`` (``--avoid-collisions`` to ``flag_group`` if given:
    a mutually exclusive group, e.g. with ``--linear``)."""
    (flag_group or parser).add_argument(
        "--avoid-collisions", action="store_true",
        help=f"plan a path that takes {what} around every arm and object in the world "
        "instead of a straight joint motion (start at rest)",
    )  # fmt: skip
    parser.add_argument(
        "--clearance", type=number_in(CLEARANCE_M), default=None, metavar="M",
        help=f"with --avoid-collisions: margin kept from other bodies [m] (default "
        f"{DEFAULT_CLEARANCE_M:g})",
    )  # fmt: skip
    parser.add_argument(
        "--planning-timeout", type=number_in(PLANNING_TIMEOUT_S), default=None, metavar="S",
        help=f"with --avoid-collisions: time budget of the plan [s] (default "
        f"{DEFAULT_TIMEOUT_S:g}); the world keeps stepping while it plans",
    )  # fmt: skip
    parser.add_argument(
        "--budget", type=number_in(PLANNING_BUDGET), default=None, metavar="N",
        help="with --avoid-collisions, instead of --planning-timeout: plan within N "
        "planner (RRT-Connect) iterations; the same request then gives the same path on "
        "any machine under any load",
    )  # fmt: skip


def planning_keywords(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments of ``move_to``/``move_to_pose``/``move_together`` for the options.

    Raises:
        UsageError: ``--clearance``, ``--planning-timeout`` or ``--budget`` without
            ``--avoid-collisions``, or ``--planning-timeout`` with ``--budget``.
    """
    if not args.avoid_collisions:
        for dest, option in _PLANNING_ONLY.items():
            if getattr(args, dest) is not None:
                raise UsageError(
                    f"{option} goes with --avoid-collisions; without it the motion is a "
                    "straight line"
                )
        return {}
    keywords: dict[str, Any] = {
        "avoid_collisions": True,
        "clearance_m": DEFAULT_CLEARANCE_M if args.clearance is None else args.clearance,
    }
    if args.budget is None:
        timeout = args.planning_timeout
        keywords["timeout_s"] = DEFAULT_TIMEOUT_S if timeout is None else timeout
    elif args.planning_timeout is not None:
        raise UsageError(
            "--planning-timeout (wall time) and --budget (planner iterations) exclude each "
            "other; give one"
        )
    else:
        keywords["budget"] = int(args.budget)
    return keywords
