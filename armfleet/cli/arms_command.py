"""``armfleet arms``: the arms of the running world and what they are doing."""

from __future__ import annotations

import argparse
from pathlib import PurePath
from typing import Any

from armfleet.cli.api_options import add_remote_command, connect_from
from armfleet.cli.number_format import fixed
from armfleet.cli.parser import OneLineParser


def add_parser(subparsers: argparse._SubParsersAction[OneLineParser]) -> None:
    parser = add_remote_command(subparsers, "arms", "list the arms of the running world")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    with connect_from(args) as client:
        arms = client.call("arms")
        info = client.info()
    print(
        f"{'name':<12} {'model':<8} {'mode':<16} {'at (x, y, z [m], yaw [deg])':<28} "
        f"{'gripper':<24} q [rad]"
    )
    for arm in arms:
        pose = arm["pose"]
        at = ", ".join([*(fixed(pose[axis], 2) for axis in "xyz"), fixed(pose["yaw_deg"], 0)])
        q = " ".join(fixed(v, 3, "+") for v in arm["positions"])
        mode = arm["mode"] + (f" ({arm['reason']})" if arm["reason"] else "")
        gripper = _gripper(arm.get("gripper"))
        model = _short_model(arm["model"])
        print(f"{arm['name']:<12} {model:<8} {mode:<16} {at:<28} {gripper:<24} [{q}]")
    state = "paused" if info.paused else "running"
    print(f"({len(arms)} arm(s); t={info.time_s:.3f}s, {state}, {client.address})")
    return 0


def _short_model(model: str) -> str:
    """A shipped model's name, or a model file's name (its folder is in ``armfleet topic
    echo /<arm>/robot_description`` and the recording)."""
    if model.startswith("package://") or "/" in model:
        return PurePath(model).name
    return model


def _gripper(state: dict[str, Any] | None) -> str:
    """E.g. ``0.0400 m holding``, ``0.9000 rad at width`` (a revolute jaw); ``-`` for an
    arm without a gripper."""
    if state is None:
        return "-"
    unit = state.get("width_unit", "m")  # worlds before revolute jaws: fingers, metres
    width = fixed(state["width"], 4)
    return f"{width} {unit} " + ("holding" if state["holding"] else state["mode"])
