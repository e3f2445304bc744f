"""Whether the world's process can read a model file a client names.

A model file given through the live API is read by the process that owns the world,
not by the client: a path that exists only on the client's machine (or in its mount
namespace, or behind permissions the world's process lacks) is refused here, before the
request reaches the world, with a line that says which process reads it. The world is
left as it was.
"""

from __future__ import annotations

import errno
import os
import socket
from pathlib import Path

from armfleet.checks.model_reference import is_model_file
from armfleet.description.model_options import ModelOptions
from armfleet.services.errors import ModelFileUnreadable

#: Reasons for the usual errors, as a user reads them.
_REASONS = {
    errno.ENOENT: "not found",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.EISDIR: "is a folder, not a file",
    errno.ENOTDIR: "not found (a part of the path is no folder)",
}


def require_readable_model_files(model: str, options: ModelOptions) -> None:
    """Raise :class:`~armfleet.services.errors.ModelFileUnreadable` if this process
    cannot open ``model`` (when it is a path, not a shipped model's name nor a
    ``package://`` URI, which this process resolves itself) or the end effector's file.

    A relative path is taken from this process's working folder, as the world takes it
    (the Python client and the CLI send absolute paths)."""
    files = [("model", model)]
    if options.end_effector is not None:
        files.append(("end_effector.file", options.end_effector.file))
    for field, file in files:
        if not is_model_file(file) or file.startswith("package://"):
            continue
        path = Path(file).expanduser()
        try:
            with path.open("rb"):
                pass
        except OSError as exc:
            reason = _REASONS.get(exc.errno or 0, exc.strerror or type(exc).__name__)
            raise ModelFileUnreadable(
                field, str(path), reason, os.getpid(), socket.gethostname()
            ) from None
