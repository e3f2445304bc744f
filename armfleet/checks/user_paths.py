"""Paths users give as text (recordings, launch specs, outputs).

``Path("")`` is the current folder, so an empty path would be read as ``.`` and the
error would speak of a folder nobody named (``. is not an MCAP recording``), or fail
deeper (``recover("")``: ValueError). One rule, for the Python API and the command line
alike: a path given as text is not empty and not only blanks.

A second rule for every file a user names to be read or written (a launch spec, a
controller parameter file, a mesh, a recording): it is a regular file. A folder, a
device (``/dev/zero`` never ends) or a FIFO (opening one nobody writes to waits for
ever) is refused, before it is opened, as what it is rather than "not found".
"""

from __future__ import annotations

import stat
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


def file_problem(path: Path, *, missing_ok: bool = False) -> str | None:
    """Why ``path`` is no regular file to open, as a phrase; None when it is one.

    The one "not a regular file" rule: ``"is a folder, not a regular file"``, ``"is a
    pipe (FIFO), not a regular file"``, ``"is a device, not a regular file"``; ``"not
    found"`` (None with ``missing_ok``, for a file about to be written); ``"cannot be
    read (<reason>)"`` when the file system refuses to say. Nothing is opened.
    """
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return None if missing_ok else "not found"
    except OSError as exc:  # a name too long, a path through a file, no permission
        return f"cannot be opened ({exc.strerror})"
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        kind = "a folder"
    elif stat.S_ISFIFO(mode):
        kind = "a pipe (FIFO)"
    elif stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        kind = "a device"
    else:
        kind = "a socket" if stat.S_ISSOCK(mode) else "a special file"
    return f"is {kind}, not a regular file"
