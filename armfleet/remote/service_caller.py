"""What a remote handle needs of its client: one call to the world's services.

:class:`~armfleet.remote.remote_arm.RemoteArm` and
:class:`~armfleet.remote.remote_gripper.RemoteGripper` call through this protocol, so
the client makes them without either importing it.
"""

from __future__ import annotations

from typing import Any, Protocol


class ServiceCaller(Protocol):
    """A connection to a running world (an :class:`armfleet.remote.Client`)."""

    def call(
        self,
        op: str,
        args: dict[str, Any] | None = None,
        timeout: float | None = None,
        *,
        work_s: float = 0.0,
    ) -> Any:
        """Send request ``op`` with ``args`` and return the world's result."""
