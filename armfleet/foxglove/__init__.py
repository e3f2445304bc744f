"""Live Foxglove: a world's topics, arms and services in the Foxglove app.

``world.serve_foxglove(port)`` (or ``armfleet spawn ... --foxglove [PORT]``) starts a
Foxglove WebSocket server (the ``foxglove-sdk`` package's) that publishes every topic
with the recording's schemas and JSON encoding, serves the arms' URDFs and meshes,
and offers ``/move``, ``/move_together``, ``/grip`` and ``/reset`` to the Service Call
panel. See docs/foxglove.md.

Rule: a front end (the ``foxglove`` extra); attaches to the world as a
:class:`~armfleet.world.WorldListener`; imports :mod:`armfleet.services`,
:mod:`armfleet.recording` (its encoders) and the core below.
"""

from __future__ import annotations

from armfleet.checks.extras import require_extra

require_extra("Foxglove live", "foxglove", "foxglove")

from armfleet.foxglove.assets import AssetLibrary, urdf_uri
from armfleet.foxglove.errors import FoxgloveError, ServiceCallError
from armfleet.foxglove.server import DEFAULT_PORT, FoxgloveServer, serve_foxglove
from armfleet.foxglove.services import SERVICE_SCHEMAS

__all__ = [
    "DEFAULT_PORT",
    "SERVICE_SCHEMAS",
    "AssetLibrary",
    "FoxgloveError",
    "FoxgloveServer",
    "ServiceCallError",
    "serve_foxglove",
    "urdf_uri",
]
