"""Argument parsing whose errors are one line, exit code 2, no traceback."""

from __future__ import annotations

import argparse
import difflib
import re
import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn


class UsageError(Exception):
    """A bad invocation; its message is the one line the user sees."""


#: Values such as ``-1,0`` or ``-0.5,2,0,-90`` are poses, not options; ``-inf`` and
#: ``-nan`` are numbers too (refused by the argument's range, in its own words).
_NEGATIVE_VALUE = re.compile(
    r"^-\d[\d.,eE+-]*$|^-\.\d[\d.,eE+-]*$|^-(inf|infinity|nan)$", re.IGNORECASE
)


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` instead of printing usage.

    It also reads ``--at 0,0 -1,0`` as two poses: argparse only lets plain
    negative numbers through, and would take ``-1,0`` for an unknown option; and a
    value that is not one of an argument's choices (a subcommand, a shape) gets a
    "did you mean" when one is close.
    """

    #: Names of the subcommands, once added.
    commands: tuple[str, ...] = ()
    #: A command's better message for a parse error, given the error and the arguments
    #: it was parsing (None: keep argparse's).
    explain: Callable[[str, Sequence[str]], str | None] | None = None

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # argparse's documented behaviour hinges on this matcher (no option of ours
        # looks like a negative number, so such values are always arguments).
        self._negative_number_matcher = _NEGATIVE_VALUE

    def parse_known_args(  # type: ignore[override]  # same behaviour, arguments kept
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self._given = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> NoReturn:
        if self.explain is not None:
            better = self.explain(message, getattr(self, "_given", []))
            if better is not None:
                raise UsageError(f"{better} (see '{self.prog} --help')")
        raise UsageError(f"{message} (see '{self.prog} --help')")

    def _check_value(self, action: argparse.Action, value: Any) -> None:
        """Refuse a value outside ``action.choices``, suggesting the closest choice."""
        choices = action.choices
        if choices is None or value in choices:
            return
        names = [str(choice) for choice in choices]
        close = difflib.get_close_matches(str(value), names, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        listed = ", ".join(repr(name) for name in names)
        raise argparse.ArgumentError(
            action, f"invalid choice: {value!r}{hint} (choose from {listed})"
        )


def fail(message: str) -> NoReturn:
    """Print ``armfleet: error: <message>`` on stderr and exit with code 2."""
    one_line = " ".join(message.split())
    print(f"armfleet: error: {one_line}", file=sys.stderr)
    raise SystemExit(2)
