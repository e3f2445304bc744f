"""Robot descriptions: xacro models, ``package://`` resolution, prefixed URDF."""

from armfleet.description.model_library import ArmDescription, ModelLibrary
from armfleet.description.resource_resolver import ResourceResolver

__all__ = ["ArmDescription", "ModelLibrary", "ResourceResolver"]
