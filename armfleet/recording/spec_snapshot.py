"""The launch spec of a recorded run, as a YAML file that ``armfleet launch`` accepts.

A spec read from a file is kept as written; one built on the command line
(``armfleet spawn``) or in Python is written out in the spec format, so every
recording says how to bring its world up again.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from armfleet.spec import FleetSpec


def spec_text(spec: FleetSpec) -> str:
    """The spec's own file text if it came from a readable file, else its YAML form."""
    source = Path(spec.source)
    if source.suffix in (".yaml", ".yml") and source.is_file():
        try:
            return source.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            pass
    return spec_yaml(spec)


def spec_yaml(spec: FleetSpec) -> str:
    """``spec`` in the launch spec format (see :mod:`armfleet.spec.spec_loader`)."""
    world = spec.world
    document: dict[str, Any] = {
        "world": {
            "dt_s": world.dt_s,
            "gravity_m_s2": world.gravity_m_s2,
            "realtime": world.realtime,
            "viewer": world.viewer,
        },
        "arms": [],
    }
    for arm in spec.arms:
        pose = arm.pose
        entry: dict[str, Any] = {
            "name": arm.name,
            "model": arm.model,
            "at_m": [pose.x, pose.y, pose.z],
        }
        if not arm.options.is_default:  # a model file and what was said about it
            entry["model"] = {"file": arm.model, **arm.options.to_mapping()}
        if pose.tilted:
            entry["rpy_deg"] = [pose.roll_deg, pose.pitch_deg, pose.yaw_deg]
        else:
            entry["yaw_deg"] = pose.yaw_deg
        if arm.initial_positions is not None:
            entry["initial_positions"] = list(arm.initial_positions)
        controllers = {
            name: {
                **({"file": str(config.file)} if config.file else {}),
                **({"parameters": dict(config.parameters)} if config.parameters else {}),
            }
            for name, config in arm.controllers.items()
        }
        if controllers:
            entry["controllers"] = controllers
        document["arms"].append(entry)
    header = f"# armfleet launch spec of a recorded run (from {spec.source})\n"
    return header + yaml.safe_dump(document, sort_keys=False)
