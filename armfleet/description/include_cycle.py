"""An include cycle in a xacro file, named: the files that include each other.

xacro does not look for cycles: a file that includes itself, directly or through others
(also by ``$(find pkg)/...``), recurses until Python's recursion limit, and
:func:`~armfleet.description.file_model.expand_file` would report "maximum recursion
depth exceeded". xacro keeps the files it is inside of on a stack (``xacro.filestack``),
left as it was when the recursion failed; the first file found twice on it closes the
cycle.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import xacro

from armfleet.errors import DescriptionError


@contextmanager
def naming_include_cycle(path: Path) -> Iterator[None]:
    """Turn a failed xacro expansion of ``path`` that ran into an include cycle into one
    line naming the files of the cycle.

    Raises:
        DescriptionError: ``path: include cycle a.xacro -> b.xacro -> a.xacro ...``, or
            the error raised inside, unchanged.
    """
    try:
        yield
    except DescriptionError as error:
        cause = error.__cause__ or error.__context__
        # Through $(find), xacro wraps the RecursionError in an error of its own.
        recursed = isinstance(cause, RecursionError) or "maximum recursion depth" in str(error)
        cycle = include_cycle(getattr(xacro, "filestack", None) or [])
        if not recursed or cycle is None:
            raise
        first = cycle[0]
        chain = " -> ".join(Path(name).name for name in cycle)
        raise DescriptionError(
            f"{path}: include cycle {chain} ({first} includes itself through them; xacro "
            "would include them forever): remove one of these includes"
        ) from None


def include_cycle(stack: Sequence[str | None]) -> list[str] | None:
    """The files from the first one found twice on ``stack`` to its repetition, or None."""
    seen: dict[str, int] = {}
    for index, name in enumerate(stack):
        if name is None:
            continue
        key = os.path.normpath(os.path.abspath(name))
        if key in seen:
            return [os.path.normpath(str(n)) for n in stack[seen[key] : index + 1] if n]
        seen[key] = index
    return None
