"""Errors a user can cause with recordings: a missing file, not an MCAP, an unknown arm."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from armfleet.errors import ArmfleetError


class RecordingError(ArmfleetError):
    """A recording that cannot be written or read."""


class RecordingNotFound(RecordingError):
    def __init__(self, path: Path) -> None:
        self.path = path
        super().__init__(f"no recording at {path}: the file does not exist")


class NotARecording(RecordingError):
    def __init__(self, path: Path, reason: str) -> None:
        self.path = path
        self.reason = reason
        super().__init__(f"{path} is not an MCAP recording ({reason})")


class UnknownRecordedArm(RecordingError):
    def __init__(self, path: Path, name: str, arms: Sequence[str], what: str = "") -> None:
        self.path = path
        self.name = name
        self.arms = tuple(arms)
        listed = ", ".join(sorted(arms)) or "(none)"
        super().__init__(f"{path} has no arm named {name!r}{what}; arms: {listed}")


class DamagedRecording(RecordingError):
    """An MCAP file whose records break off in something no MCAP writer writes.

    Attributes:
        path: the file.
        reason: what is wrong and where, e.g. ``a record of unknown type 0x5c at byte 31``.
        messages_before: whole messages before the damage (what ``armfleet recover``
            keeps); None if not counted.
    """

    def __init__(self, path: Path, reason: str, messages_before: int | None) -> None:
        self.path = path
        self.reason = reason
        self.messages_before = messages_before
        if messages_before is None:
            rescue = f"'armfleet recover {path}' saves the messages before it"
        elif messages_before:
            rescue = f"'armfleet recover {path}' saves the {messages_before} messages before it"
        else:
            rescue = "no message precedes it"
        super().__init__(f"{path} is damaged: {reason}; {rescue}")
