"""``$(find pkg)`` in xacro files, through ROS's own package index.

xacro resolves ``$(find pkg)`` with ``ament_index_python`` (ROS 2's package index, installed
from the package index with armfleet), which reads ``$AMENT_PREFIX_PATH``. While xacro
runs, :func:`ament_index` puts in front of it a prefix of armfleet's making whose index
names every package :class:`~armfleet.description.package_finder.PackageFinder` finds, each
``share/<pkg>`` a link to its folder; so ``$(find)`` and ``package://`` resolve alike.
"""

from __future__ import annotations

import os
import tempfile
import threading
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

#: The environment is the process's: one xacro run at a time changes it.
_ENVIRONMENT = threading.Lock()
_INDEX = Path("share", "ament_index", "resource_index", "packages")


@contextmanager
def ament_index(packages: Mapping[str, Path]) -> Iterator[Path]:
    """An ament prefix naming ``packages`` (name -> folder), first on ``$AMENT_PREFIX_PATH``
    for the ``with`` block; yields the prefix."""
    with tempfile.TemporaryDirectory(prefix="armfleet-ament-") as prefix_text:
        prefix = Path(prefix_text)
        (prefix / _INDEX).mkdir(parents=True)
        for name, folder in packages.items():
            if not name or "/" in name or name.startswith(".") or name == "ament_index":
                continue  # not a package name this index can hold
            (prefix / _INDEX / name).touch()
            (prefix / "share" / name).symlink_to(folder, target_is_directory=True)
        with _ENVIRONMENT:
            before = os.environ.get("AMENT_PREFIX_PATH")
            os.environ["AMENT_PREFIX_PATH"] = os.pathsep.join(p for p in (prefix_text, before) if p)
            try:
                yield prefix
            finally:
                if before is None:
                    os.environ.pop("AMENT_PREFIX_PATH", None)
                else:
                    os.environ["AMENT_PREFIX_PATH"] = before
