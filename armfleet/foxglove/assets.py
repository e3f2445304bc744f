"""The files a Foxglove client may fetch: each arm's URDF and the meshes it references.

Foxglove's 3D panel draws an arm from ``/<arm>/robot_description`` (a URDF) and
fetches its meshes through the server (``package://`` URIs, the ``fetchAsset``
operation of the WebSocket protocol). The URDF published live therefore names its
meshes ``package://<package>/<path>``, where ``<package>`` is the ``*_description``
folder the mesh lives in (``package://panda_description/meshes/visual/link0.dae``),
and the URDF itself is served as ``package://armfleet/robots/<arm>.urdf``.

Security: only the URIs of this allowlist are served, each to the one file it was
made for, compared as a whole string. Nothing is joined or normalised, so
``package://../../etc/passwd``, ``package://x/%2e%2e/...``, absolute paths,
``file://`` URIs and unknown packages are simply not in it (the handler returns
None: "not found"). A mesh is served only while its real path is still the one
resolved when its arm was added and it is a regular file: replacing it with a
symlink pointing elsewhere gets "not found" too.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import stat
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm

logger = logging.getLogger("armfleet")

#: Package of the URDFs served.
URDF_PACKAGE = "armfleet"
#: Largest file served [bytes] (Panda meshes: up to ~10 MB).
MAX_ASSET_BYTES = 128 * 1024 * 1024
_MESH_PATH = re.compile(r'filename="(/[^"]*)"')
_DESCRIPTION_FOLDER = "_description"


def urdf_uri(arm: str) -> str:
    """The URI a client fetches arm ``arm``'s live URDF at."""
    return f"package://{URDF_PACKAGE}/robots/{arm}.urdf"


@dataclass(frozen=True)
class _ArmAssets:
    urdf: bytes
    #: Mesh URI -> the real path it stands for.
    meshes: dict[str, str]


class AssetLibrary:
    """The allowlist of assets: URIs -> files, for the arms added and not removed.

    Thread-safe: arms are added and removed in the stepping thread; :meth:`fetch`
    runs in the Foxglove server's thread.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._arms: dict[str, _ArmAssets] = {}
        #: Real path -> URI, so that every arm names a shared mesh the same way.
        self._uris: dict[str, str] = {}

    def add_arm(self, arm: Arm) -> str:
        """Allow ``arm``'s URDF and meshes; return its URDF with ``package://`` mesh URIs
        (what ``/<arm>/robot_description`` publishes live)."""
        meshes: dict[str, str] = {}

        def rewrite(match: re.Match[str]) -> str:
            path = os.path.realpath(match.group(1))
            uri = self._uri_for(path)
            meshes[uri] = path
            return f'filename="{uri}"'

        with self._lock:
            urdf = _MESH_PATH.sub(rewrite, arm.description.urdf)
            self._arms[arm.name] = _ArmAssets(urdf.encode(), meshes)
        return urdf

    def remove_arm(self, name: str) -> None:
        """Stop serving arm ``name``'s URDF (and the meshes no other arm uses)."""
        with self._lock:
            self._arms.pop(name, None)

    @property
    def uris(self) -> list[str]:
        """Every URI served now, sorted."""
        with self._lock:
            served = {urdf_uri(name) for name in self._arms}
            for assets in self._arms.values():
                served.update(assets.meshes)
        return sorted(served)

    def fetch(self, uri: str) -> bytes | None:
        """The bytes of ``uri``, or None if it is not in the allowlist or its file is
        no longer the one allowed (the Foxglove server answers "not found")."""
        if not isinstance(uri, str):
            return None
        with self._lock:
            for name, assets in self._arms.items():
                if uri == urdf_uri(name):
                    return assets.urdf
            path = next((a.meshes[uri] for a in self._arms.values() if uri in a.meshes), None)
        if path is None:
            logger.info("foxglove: refused the asset %r: not a file of an arm's description", uri)
            return None
        return _read_allowed(path)

    def _uri_for(self, path: str) -> str:
        """A ``package://`` URI for the real path ``path``, the same for every arm."""
        known = self._uris.get(path)
        if known is not None:
            return known
        parts = Path(path).parts
        folder = next(
            (i for i in range(len(parts) - 2, 0, -1) if parts[i].endswith(_DESCRIPTION_FOLDER)),
            None,
        )
        if folder is not None:
            package, rest = parts[folder], "/".join(parts[folder + 1 :])
        else:  # no ROS-style package folder: a name made from the folder, stable per path
            digest = hashlib.sha1(str(Path(path).parent).encode()).hexdigest()[:10]
            package, rest = f"armfleet_files_{digest}", Path(path).name
        uri = f"package://{package}/{rest}"
        taken = set(self._uris.values())
        suffix = 2
        while uri in taken:  # the same package name in two places
            uri = f"package://{package}_{suffix}/{rest}"
            suffix += 1
        self._uris[path] = uri
        return uri


def _read_allowed(path: str) -> bytes | None:
    """The bytes of ``path`` if it is still a regular file at that real path."""
    try:
        if os.path.realpath(path) != path:  # a folder or the file became a symlink
            logger.warning("foxglove: refused %s: it is now a link elsewhere", path)
            return None
        # Non-blocking: opening a FIFO put in the file's place must not wait for a writer.
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        info = os.fstat(descriptor)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_ASSET_BYTES:
            return None
        chunks, left = [], info.st_size
        while left > 0 and (chunk := os.read(descriptor, min(left, 1 << 20))):
            chunks.append(chunk)
            left -= len(chunk)
        return b"".join(chunks)
    except OSError:
        return None
    finally:
        os.close(descriptor)
