"""Optional features and the extras that install them (pyproject.toml's
``[project.optional-dependencies]``): a missing one is one line with the pip command."""

from __future__ import annotations

from importlib.util import find_spec

from armfleet.errors import MissingExtra


def require_extra(feature: str, extra: str, *modules: str) -> None:
    """Raise :class:`~armfleet.errors.MissingExtra` unless every module of ``modules``
    (top-level import names, e.g. ``"ray"``) is installed; imports none of them."""
    for module in modules:
        try:
            found = find_spec(module) is not None
        except (ImportError, ValueError):  # a broken or blocked install is a missing one
            found = False
        if not found:
            raise MissingExtra(feature, extra, module)
