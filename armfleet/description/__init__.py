"""Robot descriptions: xacro models, ``package://`` resolution, prefixed URDF.

Rule: imports :mod:`armfleet.frames`, :mod:`armfleet.physics` and below; never a
controller, an arm or the world.
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.description.model_library import ArmDescription, ModelLibrary
    from armfleet.description.resource_resolver import ResourceResolver

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ArmDescription": "armfleet.description.model_library",
        "ModelLibrary": "armfleet.description.model_library",
        "ResourceResolver": "armfleet.description.resource_resolver",
    },
)

__all__ = ["ArmDescription", "ModelLibrary", "ResourceResolver"]
