"""Robot descriptions: xacro models, ``package://`` resolution, prefixed URDF.

Rule: imports :mod:`armfleet.frames`, :mod:`armfleet.physics` and below; never a
controller, an arm or the world.
"""

from armfleet.description.model_library import ArmDescription, ModelLibrary
from armfleet.description.resource_resolver import ResourceResolver

__all__ = ["ArmDescription", "ModelLibrary", "ResourceResolver"]
