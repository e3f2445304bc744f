"""Front ends the world starts on request, found by name among the installed plugins.

``World(viewer=True)``, ``world.record(...)`` and ``world.serve_foxglove(...)`` start a
front end that lives above the world (the viewer, a recorder, the Foxglove server).
The world finds each by its name in the ``armfleet.front_ends`` entry-point group
(pyproject.toml), the standard plugin registry of Python packaging, so the world names
no front end, and another package can add its own.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any, Protocol

from armfleet.errors import ArmfleetError
from armfleet.messages import PlannedMotion

#: The entry-point group front ends register in.
FRONT_ENDS_GROUP = "armfleet.front_ends"


def front_end(name: str) -> Callable[..., Any]:
    """The starter registered as ``name`` (it takes the world first).

    Raises:
        ArmfleetError: no front end of that name is installed (the others listed), or
            its optional dependencies are missing (the pip command to add them).
    """
    found = entry_points(group=FRONT_ENDS_GROUP)
    for point in found:
        if point.name == name:
            starter: Callable[..., Any] = point.load()
            return starter
    available = ", ".join(sorted(point.name for point in found)) or "none"
    raise ArmfleetError(
        f"no armfleet front end {name!r} is installed; installed: {available} "
        f"(reinstall armfleet: pip install .)"
    )


class ViewerHandle(Protocol):
    """What ``world.viewer`` offers: the public face of :class:`armfleet.viewer.Viewer`."""

    @property
    def url(self) -> str:
        """The page to open in a browser."""
        ...

    @property
    def port(self) -> int:
        """Its web port."""
        ...

    @property
    def zmq_port(self) -> int:
        """The MeshCat server's ZMQ port."""
        ...

    @property
    def server_pid(self) -> int:
        """Process id of its MeshCat server."""
        ...

    @property
    def error(self) -> str | None:
        """Why it stopped showing the world, or None."""
        ...

    @property
    def closed(self) -> bool:
        """Closed with the world or by :meth:`close`."""
        ...

    @property
    def arms(self) -> tuple[str, ...]:
        """The arms it draws."""
        ...

    @property
    def objects(self) -> tuple[str, ...]:
        """The objects it draws."""
        ...

    @property
    def batches_sent(self) -> int:
        """Pose batches sent to the browser so far."""
        ...

    @property
    def planned_motions(self) -> dict[str, PlannedMotion]:
        """The planned motion it shows per arm."""
        ...

    def expect_arms(self, positions: Mapping[str, Sequence[float]]) -> None:
        """Frame the arms about to come (name -> base x, y, z [m]) before their meshes."""

    def show_frames(self, visible: bool = True) -> None:
        """Show or hide the TF frames."""

    def show_targets(self, visible: bool = True) -> None:
        """Show or hide the arms' targets."""

    def refresh(self, timeout_s: float = 5.0) -> bool:
        """Send the current poses now; False if the server did not answer in time."""
        ...

    def save(self, path: str | Path) -> Path:
        """Write what it recorded as a self-contained HTML page."""
        ...

    def close(self) -> None:
        """Stop its server."""
