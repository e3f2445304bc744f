"""Argument parsing whose errors are one line, exit code 2, no traceback."""

from __future__ import annotations

import argparse
import sys
from typing import NoReturn


class UsageError(Exception):
    """A bad invocation; its message is the one line the user sees."""


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` instead of printing usage."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{message} (see '{self.prog} --help')")


def fail(message: str) -> NoReturn:
    """Print ``armfleet: error: <message>`` on stderr and exit with code 2."""
    print(f"armfleet: error: {message}", file=sys.stderr)
    raise SystemExit(2)
