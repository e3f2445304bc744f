"""Where ROS packages are, looked up as ROS users expect: ``package://pkg/...`` and
``$(find pkg)`` in a description.

Places, in search order:

1. folders given by the caller (``--package-path DIR``, ``package_paths=``);
2. ``$ARMFLEET_PACKAGE_PATH``;
3. ``$ROS_PACKAGE_PATH``;
4. the ``share/`` folder of every prefix in ``$AMENT_PREFIX_PATH``;
5. example-robot-data's ``share/`` folder (installed with armfleet).

A place is a package itself (its ``package.xml`` names it), or holds packages: a folder
named after the package directly in it, or a ``package.xml`` naming it up to
:data:`SEARCH_DEPTH` folders down (as ``rospack`` finds packages in a workspace's
``src/``). The first match wins. An unresolved package is one line naming it and every
place searched.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from armfleet.errors import PackageNotFound

PACKAGE_PATH_ENV = "ARMFLEET_PACKAGE_PATH"
#: Folders below a place searched for a ``package.xml`` naming the package.
SEARCH_DEPTH = 3
_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


@dataclass(frozen=True)
class Place:
    """A folder searched for packages, and where it came from (for error messages)."""

    folder: Path
    origin: str

    def __str__(self) -> str:
        return f"{self.folder} ({self.origin})"


def _env_paths(variable: str) -> list[Path]:
    return [Path(p) for p in os.environ.get(variable, "").split(os.pathsep) if p]


def default_places(package_paths: Sequence[str | Path] = ()) -> list[Place]:
    """Every place searched, in order (see the module docstring)."""
    places = [Place(Path(p).expanduser(), "--package-path") for p in package_paths]
    places += [Place(p, PACKAGE_PATH_ENV) for p in _env_paths(PACKAGE_PATH_ENV)]
    places += [Place(p, "ROS_PACKAGE_PATH") for p in _env_paths("ROS_PACKAGE_PATH")]
    places += [Place(p / "share", "AMENT_PREFIX_PATH") for p in _env_paths("AMENT_PREFIX_PATH")]
    try:
        share = metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share")
        places.append(Place(Path(str(share)), "example-robot-data"))
    except metadata.PackageNotFoundError:
        pass
    return places


def package_name(folder: Path) -> str | None:
    """The name ``folder/package.xml`` gives, or None if there is none (or no name)."""
    manifest = folder / "package.xml"
    try:
        found = _NAME.search(manifest.read_text(encoding="utf-8", errors="replace"))
    except OSError:
        return None
    return found.group(1) if found else None


class PackageFinder:
    """Finds the folder of a ROS package in :func:`default_places`.

    Args:
        package_paths: folders searched first (``--package-path``).
    """

    def __init__(self, package_paths: Sequence[str | Path] = ()) -> None:
        self._places = tuple(default_places(package_paths))
        self._found: dict[str, Path] = {}

    @property
    def places(self) -> tuple[Place, ...]:
        return self._places

    def find(self, package: str) -> Path:
        """The folder of ``package``.

        Raises:
            PackageNotFound: naming the package and every place searched.
        """
        if package in self._found:
            return self._found[package]
        for place in self._places:
            found = _find_in(place.folder, package)
            if found is not None:
                self._found[package] = found
                return found
        raise PackageNotFound(package, [str(place) for place in self._places])

    def packages(self) -> dict[str, Path]:
        """Every package the places hold, first place first (for ``$(find)``'s index)."""
        found: dict[str, Path] = {}
        for place in self._places:
            for name, folder in _packages_in(place.folder):
                found.setdefault(name, folder)
            if place.folder.is_dir() and package_name(place.folder) is None:
                for child in sorted(place.folder.iterdir()):
                    if child.is_dir() and not child.name.startswith("."):
                        found.setdefault(child.name, child.resolve())  # share/<pkg>
        return found


def _find_in(folder: Path, package: str) -> Path | None:
    if not folder.is_dir():
        return None
    if package_name(folder) == package:
        return folder.resolve()
    direct = folder / package
    if direct.is_dir():
        return direct.resolve()
    for name, candidate in _packages_in(folder):
        if name == package:
            return candidate
    return None


def _packages_in(folder: Path, depth: int = SEARCH_DEPTH) -> Iterator[tuple[str, Path]]:
    """``(name, folder)`` of each package at or below ``folder`` (a package holds no other)."""
    if not folder.is_dir():
        return
    name = package_name(folder)
    if name is not None:
        yield name, folder.resolve()
        return
    if depth == 0:
        return
    try:
        children = sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith("."))
    except OSError:
        return
    for child in children:
        yield from _packages_in(child, depth - 1)
