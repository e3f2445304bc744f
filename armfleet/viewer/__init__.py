"""MeshCat viewer: every arm of a world live in the browser, on 127.0.0.1 only.

>>> world = armfleet.World(viewer=True)       # doctest: +SKIP
>>> print(world.viewer.url)                    # doctest: +SKIP
http://127.0.0.1:45321/static/

Importing this package is cheap: MeshCat, Pinocchio's visualizer, ZMQ and
tornado load only when a viewer starts.

Rule: a front end; attaches to the world as a :class:`~armfleet.world.WorldListener`
(:mod:`~armfleet.viewer.world_link`); imports the world and the core below.
"""

from typing import TYPE_CHECKING

from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.viewer.errors import ViewerError, ViewerTimeout
    from armfleet.viewer.viewer import DISPLAY_RATE_HZ, Viewer, start_viewer

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ViewerError": "armfleet.viewer.errors",
        "ViewerTimeout": "armfleet.viewer.errors",
        "DISPLAY_RATE_HZ": "armfleet.viewer.viewer",
        "Viewer": "armfleet.viewer.viewer",
        "start_viewer": "armfleet.viewer.viewer",
    },
)

__all__ = ["DISPLAY_RATE_HZ", "Viewer", "ViewerError", "ViewerTimeout", "start_viewer"]
