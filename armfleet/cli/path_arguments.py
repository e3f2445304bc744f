"""The argparse ``type=`` of every path a command takes (recordings, specs, outputs).

An empty path would otherwise become ``.`` (``Path("")`` is the current folder). It is
refused while the arguments are parsed, by the rule of :mod:`armfleet.checks.user_paths`, in
the argument's own name, e.g. ``argument RUN.mcap: the path is empty; give a file path``.
"""

from __future__ import annotations

import argparse

from armfleet.checks.user_paths import empty_path_problem


def path_text(text: str) -> str:
    """A path as given, unless it names no path (empty or blank).

    Raises:
        argparse.ArgumentTypeError: the path is empty (or blank).
    """
    problem = empty_path_problem(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{problem}; give a file path")
    return text


path_text.__name__ = "path"
