"""Which home a model file's arm got, and why: the clause its start line ends with."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


class HomeSource(Enum):
    """Where a model file's home came from."""

    GIVEN = "given"
    #: Every arm joint at zero, clamped into its limits (clear of itself and the floor).
    ZERO = "zero"
    #: The zero pose touched something; a clear pose near it was searched for.
    SEARCHED = "searched"


@dataclass(frozen=True)
class HomeChoice:
    """The home chosen for a model file.

    Attributes:
        source: given, zero or searched.
        reason: with ``SEARCHED``, what the zero pose touched (``"itself (a / b)"``).
    """

    source: HomeSource
    reason: str = ""

    @property
    def clause(self) -> str:
        """E.g. ``home: given``, ``home: zero pose``, ``home: searched (the zero pose
        touches the floor (link4))``."""
        if self.source is HomeSource.GIVEN:
            return "home: given"
        if self.source is HomeSource.ZERO:
            return "home: zero pose"
        return f"home: searched (the zero pose touches {self.reason})"

    @property
    def text(self) -> str:
        """One word and the reason, as the written wrapper stores it (:meth:`parse`)."""
        return f"{self.source.value} {self.reason}".strip()

    @classmethod
    def parse(cls, text: str) -> HomeChoice | None:
        """The choice :attr:`text` wrote; None for an empty text (a shipped model)."""
        word, _, reason = text.strip().partition(" ")
        if not word:
            return None
        return cls(HomeSource(word), reason)
