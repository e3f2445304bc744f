"""What a ``model`` a user gives names: a shipped model (``panda``) or a description file of
their own (a ``.urdf`` / ``.xacro`` path, or a ``package://pkg/path`` URI)."""

from __future__ import annotations

#: Suffixes of a description file.
DESCRIPTION_SUFFIXES = (".urdf", ".xacro")


def is_model_file(model: str) -> bool:
    """Whether ``model`` names a file or a ``package://`` URI rather than a shipped model."""
    return (
        model.startswith("package://")
        or "/" in model
        or model.endswith(DESCRIPTION_SUFFIXES)
        or model.startswith(("~", "."))
    )
