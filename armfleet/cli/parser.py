"""Argument parsing whose errors are one line, exit code 2, no traceback."""

from __future__ import annotations

import argparse
import difflib
import re
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from armfleet.cli.misplaced_values import (
    ValueTest,
    find_misplaced,
    is_option,
    missing_positionals,
    option_action,
)
from armfleet.cli.number_arguments import NumberArgument


class UsageError(Exception):
    """A bad invocation; its message is the one line the user sees."""


#: Values such as ``-1,0`` or ``-0.5,2,0,-90`` are poses, not options; ``-inf`` and
#: ``-nan`` are numbers too (refused by the argument's range, in its own words).
_NEGATIVE_VALUE = re.compile(
    r"^-\d[\d.,eE+-]*$|^-\.\d[\d.,eE+-]*$|^-(inf|infinity|nan)$", re.IGNORECASE
)


class RangeHelpFormatter(argparse.HelpFormatter):
    """Help that ends each numeric option's line with its valid range: the range its
    :class:`NumberArgument` checks, or the one the parser's ``help_ranges`` gives for a
    number the world checks (so neither can drift from the check)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        #: Valid ranges of numbers not typed by a NumberArgument, by argument ``dest``.
        self.ranges: dict[str, str] = {}

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = super()._get_help_string(action)
        if isinstance(action.type, NumberArgument):
            return f"{text or ''}; valid: {action.type.valid.valid}"
        if action.dest in self.ranges:
            return f"{text or ''}; valid: {self.ranges[action.dest]}"
        return text


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` instead of printing usage.

    It also reads ``--at 0,0 -1,0`` as two poses: argparse only lets plain
    negative numbers through, and would take ``-1,0`` for an unknown option; a
    value that is not one of an argument's choices (a subcommand, a shape) and an
    unknown option get a "did you mean" when one is close; positional arguments taken
    by an option of several values are named as such (see
    :mod:`armfleet.cli.misplaced_values`); and the help shows each numeric option's range.

    After a successful parse, the namespace's ``misplaced_values`` is the
    :class:`~armfleet.cli.misplaced_values.Misplaced` values of an option of several
    values, or None: a command whose counts then disagree (``spawn``'s names and poses)
    says that, rather than the counts.
    """

    #: Names of the subcommands, once added.
    commands: tuple[str, ...] = ()

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", RangeHelpFormatter)
        #: The valid range of a number the world checks rather than the parser, by the
        #: argument's ``dest``, for the help (built from the range that checks it); set
        #: first, as argparse formats its own --help while it is built.
        self.help_ranges: dict[str, str] = {}
        super().__init__(*args, **kwargs)
        # argparse's documented behaviour hinges on this matcher (no option of ours
        # looks like a negative number, so such values are always arguments).
        self._negative_number_matcher = _NEGATIVE_VALUE
        #: What an option of several values accepts, by its first option string, when
        #: its ``type=`` or ``choices`` don't say.
        self.value_tests: dict[str, ValueTest] = {}
        self._given: list[str] = []

    def parse_known_args(  # type: ignore[override]  # same behaviour, arguments kept
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self._given = list(sys.argv[1:] if args is None else args)
        self._check_options()
        parsed, extras = super().parse_known_args(args, namespace)
        misplaced = find_misplaced(self, self._given, self.value_tests, self.prog)
        if misplaced is not None or not hasattr(parsed, "misplaced_values"):
            parsed.misplaced_values = misplaced
        return parsed, extras

    def parse_args(  # type: ignore[override]  # same behaviour, one message for extras
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        """As argparse's, but arguments left over are named with the (sub)command that
        did not take them, and its help (argparse pointed to the top-level help)."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            prog = self.prog
            for action in self._actions:
                if isinstance(action, argparse._SubParsersAction):
                    command = action.choices.get(getattr(parsed, action.dest, None) or "")
                    prog = command.prog if command is not None else prog
            listed = " ".join(repr(extra) for extra in extras)
            what = "argument" if len(extras) == 1 else "arguments"
            raise UsageError(f"'{prog}' does not take the {what} {listed} (see '{prog} --help')")
        return parsed

    def error(self, message: str) -> NoReturn:
        if missing_positionals(self, self._given):
            misplaced = find_misplaced(self, self._given, self.value_tests, self.prog)
            if misplaced is not None:
                message = str(misplaced)
        raise UsageError(f"{message} (see '{self.prog} --help')")

    def _get_formatter(self) -> argparse.HelpFormatter:
        formatter = super()._get_formatter()
        if isinstance(formatter, RangeHelpFormatter):
            formatter.ranges = self.help_ranges
        return formatter

    def _check_options(self) -> None:
        """Refuse an option this (sub)command does not have, before argparse reports a
        missing argument instead, suggesting the closest of its own options; and an option
        with values given twice (argparse keeps the last: ``--at 0,0 --at 1,0`` dropped
        the first pose)."""
        has_commands = any(isinstance(a, argparse._SubParsersAction) for a in self._actions)
        seen: dict[argparse.Action, str] = {}
        for text in self._given:
            if text == "--":
                return
            if not is_option(self, text):
                if has_commands:
                    return  # the command's own options are its parser's to check
                continue
            action = option_action(self, text)
            if action is not None:
                if action.nargs != 0 and action in seen:
                    several = " (all its values after one)" if action.nargs in ("+", "*") else ""
                    self.error(f"{seen[action]} is given twice; give it once{several}")
                seen[action] = action.option_strings[-1]
                continue
            name = text.split("=", 1)[0]
            options = [o for a in self._actions for o in a.option_strings if o.startswith("--")]
            close = difflib.get_close_matches(name, options, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            self.error(f"unknown option {name!r}{hint} (options: {', '.join(options)})")

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


#: A word of an error line longer than this is cut (a 100 kB name, path or address echoed
#: back made a 100 kB "one-line" error) [characters].
LONGEST_WORD = 160
#: What is kept of such a word [characters].
KEPT_OF_WORD = 96


def one_line(message: str) -> str:
    """``message`` on one line, every word longer than :data:`LONGEST_WORD` cut short."""
    return " ".join(
        word if len(word) <= LONGEST_WORD else f"{word[:KEPT_OF_WORD]}...({len(word)} characters)"
        for word in message.split()
    )


def fail(message: str) -> NoReturn:
    """Print ``armfleet: error: <message>`` on stderr and exit with code 2."""
    print(f"armfleet: error: {one_line(message)}", file=sys.stderr)
    raise SystemExit(2)
