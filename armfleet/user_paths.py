"""Paths users give as text (recordings, launch specs, outputs).

``Path("")`` is the current folder, so an empty path would be read as ``.`` and the
error would speak of a folder nobody named (``. is not an MCAP recording``), or fail
deeper (``recover("")``: ValueError). One rule, for the Python API and the command line
alike: a path given as text is not empty and not only blanks.
"""

from __future__ import annotations

from pathlib import Path

from armfleet.errors import ArmfleetError


class EmptyPath(ArmfleetError):
    """A path given as empty (or blank) text.

    Attributes:
        what: what the path was for (``"recording"``, ``"launch spec"``).
        text: the text given.
    """

    def __init__(self, what: str, text: str) -> None:
        self.what, self.text = what, text
        super().__init__(f"{what}: {empty_path_problem(text)}; give a file path")


def empty_path_problem(text: str) -> str | None:
    """``"the path is empty"`` (or blank) when ``text`` names no path; None when it does."""
    if text.strip():
        return None
    return "the path is empty" if not text else f"the path is blank ({text!r})"


def given_path(path: str | Path, what: str) -> Path:
    """``path`` as a :class:`Path`, unless it is text that names no path.

    Args:
        path: what the user gave (a ``Path`` is taken as is: ``Path("")`` already is ``.``).
        what: what the path is for, for the message.

    Raises:
        EmptyPath: ``path`` is empty or blank text.
    """
    if isinstance(path, str) and empty_path_problem(path) is not None:
        raise EmptyPath(what, path)
    return Path(path)
