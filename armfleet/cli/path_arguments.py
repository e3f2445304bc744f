"""The argparse ``type=`` of every path a command takes (recordings, specs, outputs).

An empty path would otherwise become ``.`` (``Path("")`` is the current folder), and
the command would then speak of a folder nobody typed. Such a path is refused while the
arguments are parsed, in the argument's own name, e.g. ``argument RUN.mcap: the path is
empty; give a file path``.
"""

from __future__ import annotations

import argparse


def path_text(text: str) -> str:
    """A path as given, unless it is empty or only blanks.

    Raises:
        argparse.ArgumentTypeError: the path is empty (or blank).
    """
    if not text.strip():
        what = "empty" if not text else f"blank ({text!r})"
        raise argparse.ArgumentTypeError(f"the path is {what}; give a file path")
    return text


path_text.__name__ = "path"
