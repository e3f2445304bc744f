"""Launch specs: a world and its arms, from YAML or from the command line.

Rule: imports :mod:`armfleet.arms` (a spec is rehearsed as arms are assembled) and
the core below; never the world.
"""

from armfleet.spec.fleet_spec import ArmSpec, ControllerConfig, FleetSpec, WorldSpec
from armfleet.spec.spec_error import SpecError
from armfleet.spec.spec_loader import find_spec, load_spec, parse_spec

__all__ = [
    "ArmSpec",
    "ControllerConfig",
    "FleetSpec",
    "SpecError",
    "WorldSpec",
    "find_spec",
    "load_spec",
    "parse_spec",
]
