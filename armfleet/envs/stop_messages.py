"""An environment's stops kept in ``info`` instead of printed at every one.

An arm that stops on a contact logs ``"<arm>: protective stop: <reason>"`` as a warning
on the package logger (and a fault ``"<arm>: error: <reason>"`` as an error). With no
logging configured, Python prints warnings to stderr: in training, one line per stop,
thousands of them. While an environment steps, :class:`StopMessages` takes these records
of its own arms, in its own thread, off the package logger: their reasons go in the
step's ``info["stop_reasons"]`` and to the ``armfleet.envs`` logger at ``DEBUG``
(``logging.getLogger("armfleet.envs").setLevel(logging.DEBUG)`` and a handler show them).
Any other record, and those of other threads and worlds, pass as before.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

#: The package logger the arms log their stops on.
PACKAGE_LOGGER = logging.getLogger("armfleet")
#: Where an environment logs the stops it took (at DEBUG).
ENV_LOGGER = logging.getLogger("armfleet.envs")
_KINDS = ("protective stop", "error")


class StopMessages(logging.Filter):
    """Takes the stop and fault records of ``arms`` logged by the current thread.

    Args:
        arms: the environment's arm names.
    """

    def __init__(self, arms: Iterable[str]) -> None:
        super().__init__()
        self._prefixes = {
            f"{arm}: {kind}: ": arm for arm in arms for kind in _KINDS
        }  # fmt: skip
        self._thread = threading.get_ident()
        #: Arm -> the reason of its latest stop or fault taken.
        self.reasons: dict[str, str] = {}

    def filter(self, record: logging.LogRecord) -> bool:
        if record.thread != self._thread or record.levelno < logging.WARNING:
            return True
        message = record.getMessage()
        for prefix, arm in self._prefixes.items():
            if message.startswith(prefix):
                self.reasons[arm] = message[len(prefix) :]
                ENV_LOGGER.debug("%s", message)
                return False
        return True

    @contextmanager
    def taking(self) -> Iterator[dict[str, str]]:
        """Take the records while the block runs; yields the reasons taken (filled in as
        they come)."""
        self._thread = threading.get_ident()
        self.reasons = {}
        PACKAGE_LOGGER.addFilter(self)
        try:
            yield self.reasons
        finally:
            PACKAGE_LOGGER.removeFilter(self)
