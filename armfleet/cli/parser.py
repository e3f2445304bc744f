"""Argument parsing whose errors are one line, exit code 2, no traceback."""

from __future__ import annotations

import argparse
import re
import sys
from typing import Any, NoReturn


class UsageError(Exception):
    """A bad invocation; its message is the one line the user sees."""


#: Values such as ``-1,0`` or ``-0.5,2,0,-90`` are poses, not options.
_NEGATIVE_VALUE = re.compile(r"^-\d[\d.,eE+-]*$|^-\.\d[\d.,eE+-]*$")


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` instead of printing usage.

    It also reads ``--at 0,0 -1,0`` as two poses: argparse only lets plain
    negative numbers through, and would take ``-1,0`` for an unknown option.
    """

    #: Names of the subcommands, once added.
    commands: tuple[str, ...] = ()

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # argparse's documented behaviour hinges on this matcher (no option of ours
        # looks like a negative number, so such values are always arguments).
        self._negative_number_matcher = _NEGATIVE_VALUE

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{message} (see '{self.prog} --help')")


def fail(message: str) -> NoReturn:
    """Print ``armfleet: error: <message>`` on stderr and exit with code 2."""
    one_line = " ".join(message.split())
    print(f"armfleet: error: {one_line}", file=sys.stderr)
    raise SystemExit(2)
