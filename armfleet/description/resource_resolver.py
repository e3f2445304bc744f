"""One resolver for ``package://`` and ``file://`` URIs.

Physics, kinematics and the viewer all load the URDF text this resolver
produced, so they read the very same absolute mesh paths.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path

from armfleet.description.package_finder import PACKAGE_PATH_ENV, PackageFinder
from armfleet.errors import PackageNotFound, ResourceNotFound

_URI = re.compile(r"""(?P<quote>["'])(?P<uri>(?:package|file)://[^"']+)(?P=quote)""")


def default_share_dirs() -> list[Path]:
    """Share folders that hold ``<package>/...`` trees, in search order.

    ``$ARMFLEET_PACKAGE_PATH`` first, then the ``share`` folder of the installed
    example-robot-data (a cmeel package: ``<site-packages>/cmeel.prefix/share``).
    """
    dirs = [Path(p) for p in os.environ.get(PACKAGE_PATH_ENV, "").split(os.pathsep) if p]
    try:
        share = metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share")
        dirs.append(Path(str(share)))
    except metadata.PackageNotFoundError:
        pass
    return dirs


class ResourceResolver:
    """Turns ``package://pkg/rel/path`` and ``file:///abs`` into absolute paths.

    Args:
        share_dirs: if given, the only folders searched, in order: ``package://pkg/x``
            resolves to the first ``<dir>/pkg/x`` that exists.
        finder: else, where packages are found (``--package-path``,
            ``ARMFLEET_PACKAGE_PATH``, ``ROS_PACKAGE_PATH``, ``AMENT_PREFIX_PATH``,
            example-robot-data: :mod:`~armfleet.description.package_finder`); a default
            one if omitted.
    """

    def __init__(
        self, share_dirs: Sequence[Path] | None = None, finder: PackageFinder | None = None
    ) -> None:
        self._share_dirs = tuple(Path(d) for d in share_dirs or ())
        self._finder = finder or PackageFinder()

    @property
    def finder(self) -> PackageFinder:
        return self._finder

    @property
    def share_dirs(self) -> tuple[Path, ...]:
        """The folders searched: the ones given, else the finder's places."""
        return self._share_dirs or tuple(place.folder for place in self._finder.places)

    def resolve(self, uri: str) -> Path:
        """Absolute path of an existing file named by ``uri``.

        Raises:
            ResourceNotFound: naming the URI and every folder searched.
        """
        if uri.startswith("file://"):
            path = Path(uri[len("file://") :])
            if path.is_file():
                return path
            raise ResourceNotFound(uri, [str(path.parent)])
        if not uri.startswith("package://"):
            path = Path(uri)
            if path.is_absolute() and path.is_file():
                return path
            raise ResourceNotFound(uri, [])
        relative = uri[len("package://") :]
        if self._share_dirs:
            searched = []
            for share in self._share_dirs:
                candidate = share / relative
                searched.append(str(share))
                if candidate.is_file():
                    return candidate.resolve()
            raise ResourceNotFound(uri, searched)
        package, _, inside = relative.partition("/")
        try:
            candidate = self._finder.find(package) / inside
        except PackageNotFound as missing:
            raise ResourceNotFound(uri, missing.searched) from None
        if candidate.is_file():
            return candidate.resolve()
        raise ResourceNotFound(uri, [str(candidate.parent)])

    def resolve_text(self, xml_text: str) -> str:
        """Replace every quoted ``package://``/``file://`` URI in ``xml_text``."""

        def replace(match: re.Match[str]) -> str:
            quote = match.group("quote")
            return f"{quote}{self.resolve(match.group('uri'))}{quote}"

        return _URI.sub(replace, xml_text)
