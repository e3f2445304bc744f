"""A sweep's results file, checked before anything starts (as a recording's path is).

A sweep writes three files: the results (``RESULTS.parquet``), its journal beside it
while it runs (``RESULTS.parquet.journal``) and at the end the plot (``RESULTS.png``).
Each must be a regular file or not exist yet, and the folder must take a new file: that
is tried, with a probe file made and removed at once, because permission bits do not
say it (root may "write" to ``/proc``, where no file can be made, and a read-only file
system passes ``os.access``). So a bad ``-o`` is one line before Ray starts, not an
error after its runs.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path

from armfleet.checks.user_paths import file_problem, given_path
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.results_file import journal_path


def results_path(output: str | Path, resume: bool, overwrite: bool) -> Path:
    """``output`` as the results file of a sweep, once it is known to be writable.

    Args:
        output: the path given (``-o``).
        resume: the sweep continues the file's runs (it may exist).
        overwrite: the sweep replaces the file (it may exist; its journal is removed).

    Raises:
        SweepError: not a ``.parquet`` name, a folder that does not exist or takes no new
            file, a results, journal or plot path that is not a regular file, or a file
            that exists without ``resume`` or ``overwrite``.
    """
    path = given_path(output, "results file")
    named = str(output)
    if path.suffix != ".parquet":
        raise SweepError(f"results file {named!r}: give a .parquet file")
    folder = path.parent
    if not folder.is_dir():
        problem = file_problem(folder)
        what = "not found" if problem == "not found" else "is not a folder"
        raise SweepError(f"results file {named!r}: folder {str(folder)!r} {what}")
    for file, role in (
        (path, "results file"),
        (journal_path(path), "its journal"),
        (path.with_suffix(".png"), "its plot"),
    ):
        problem = file_problem(file, missing_ok=True)
        if problem is not None:
            raise SweepError(f"results file {named!r}: {role} {str(file)!r} {problem}")
    problem = new_file_problem(folder)
    if problem is not None:
        raise SweepError(f"results file {named!r}: folder {str(folder)!r} {problem}")
    exists = file_problem(path) is None or file_problem(journal_path(path)) is None
    if exists and not resume and not overwrite:
        raise SweepError(
            f"{path} exists; --resume runs the seeds it lacks, --overwrite replaces it, or "
            "give another -o"
        )
    if exists and overwrite:
        journal_path(path).unlink(missing_ok=True)
    return path


def new_file_problem(folder: Path) -> str | None:
    """Why no new file can be made in ``folder``, as a phrase; None when one can (a probe
    file is made and removed)."""
    probe = folder / f".armfleet-probe-{uuid.uuid4().hex}"
    try:
        descriptor = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
    except OSError as exc:
        return f"takes no new file ({exc.strerror or type(exc).__name__})"
    os.close(descriptor)
    probe.unlink(missing_ok=True)
    return None
