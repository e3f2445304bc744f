"""Launch specs: a world and its arms, from YAML or from the command line.

Rule: imports :mod:`armfleet.arms` (a spec is rehearsed as arms are assembled) and
the core below; never the world.
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.spec.fleet_spec import ArmSpec, ControllerConfig, FleetSpec, WorldSpec
    from armfleet.spec.spec_error import SpecError
    from armfleet.spec.spec_loader import find_spec, load_spec, parse_spec

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ArmSpec": "armfleet.spec.fleet_spec",
        "ControllerConfig": "armfleet.spec.fleet_spec",
        "FleetSpec": "armfleet.spec.fleet_spec",
        "WorldSpec": "armfleet.spec.fleet_spec",
        "SpecError": "armfleet.spec.spec_error",
        "find_spec": "armfleet.spec.spec_loader",
        "load_spec": "armfleet.spec.spec_loader",
        "parse_spec": "armfleet.spec.spec_loader",
    },
)

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
