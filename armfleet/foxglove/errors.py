"""Errors of the Foxglove server: it could not start, or a service call was refused."""

from __future__ import annotations

from armfleet.errors import ArmfleetError


class FoxgloveError(ArmfleetError):
    """The Foxglove server could not start (address in use, bad bind address, closed world)."""


class ServiceCallError(ArmfleetError):
    """A Foxglove service call that could not be served: its request is not JSON, its
    encoding is not ``json``, or the world did not answer in time.

    Attributes:
        service: the service called (``/move``...).
    """

    def __init__(self, service: str, problem: str) -> None:
        self.service = service
        super().__init__(f"{service}: {problem}")
