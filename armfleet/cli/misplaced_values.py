"""Positional arguments taken by an option of several values.

An option with ``nargs="+"`` (``spawn --at``, ``spawn --model``, ``move --joints``, ``plot
--arm``) takes every value up to the next option, so the names typed after it end up
as its values, and argparse then says a positional argument is missing, or that the
option's value is invalid. The same rule serves every such option: the values the option
does not accept were meant as positional arguments; the message says so, with the
command line rearranged.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

#: ``nargs`` of the options that take every value up to the next option.
MANY = ("+", "*")


@dataclass(frozen=True)
class ValueTest:
    """What an option of several values takes, when its ``type=`` or ``choices`` don't say.

    Attributes:
        noun: one value, for messages (``"position"``, ``"model"``).
        accepts: whether a text is such a value (False: a misplaced positional).
    """

    noun: str
    accepts: Callable[[str], bool]


@dataclass(frozen=True)
class Misplaced:
    """Values an option took that it does not accept.

    Attributes:
        option: the option (``"--at"``).
        values: the values it does not accept.
        noun: one value of the option, for the message.
        positionals: the metavars of the positional arguments (``"NAME"``).
        example: the command line with ``values`` moved before the first option.
    """

    option: str
    values: tuple[str, ...]
    noun: str
    positionals: tuple[str, ...]
    example: str

    def __str__(self) -> str:
        article = "an" if self.noun[:1] in "aeiou" else "a"
        what = f"{article} {self.noun}" if len(self.values) == 1 else f"{self.noun}s"
        taken = ", ".join(repr(value) for value in self.values)
        wanted = " ".join(self.positionals) or "the arguments"
        return (
            f"{self.option} took {taken} as {what}; put {wanted} before {self.option}, "
            f"e.g. '{self.example}'"
        )


def is_option(parser: argparse.ArgumentParser, text: str) -> bool:
    """Whether argparse reads ``text`` as an option (not a value such as ``-1,0``)."""
    if len(text) < 2 or text[0] not in parser.prefix_chars or " " in text:
        return False
    return not parser._negative_number_matcher.match(text)


def option_action(parser: argparse.ArgumentParser, text: str) -> argparse.Action | None:
    """The action of the option ``text`` (``--at``, ``--at=0,0``, ``--mod``, ``-ofile``);
    None when the parser has no such option."""
    actions = parser._option_string_actions
    name = text.split("=", 1)[0]
    if name in actions:
        return actions[name]
    if not name.startswith("--"):
        return actions.get(name[:2])  # -ofile: -o with its value attached
    if parser.allow_abbrev:
        matches = {actions[option] for option in actions if option.startswith(name)}
        if len(matches) == 1:
            return matches.pop()
    return None


def _default_test(action: argparse.Action) -> ValueTest | None:
    convert = action.type
    if callable(convert):

        def converts(text: str) -> bool:
            try:
                convert(text)
            except (ValueError, TypeError, argparse.ArgumentTypeError):
                return False
            return True

        return ValueTest("value", converts)
    if action.choices is not None:
        choices = action.choices
        return ValueTest("value", lambda text: text in choices)
    return None


def find_misplaced(
    parser: argparse.ArgumentParser,
    given: Sequence[str],
    tests: Mapping[str, ValueTest],
    prog: str,
) -> Misplaced | None:
    """The first option of several values in ``given`` that took values it does not accept.

    Args:
        parser: the (sub)command's parser.
        given: the arguments it parses.
        tests: what an option accepts, by its first option string, for the options whose
            ``type=`` or ``choices`` don't say (without one, an option accepts anything).
        prog: the command, for the example.
    """
    taken, _ = _split(parser, given)
    for action, indices in taken.items():
        test = tests.get(action.option_strings[0]) or _default_test(action)
        if test is None:
            continue
        refused = [index for index in indices if not test.accepts(given[index])]
        if refused:
            return Misplaced(
                option=action.option_strings[0],
                values=tuple(given[index] for index in refused),
                noun=test.noun,
                positionals=tuple(
                    str(a.metavar or a.dest) for a in parser._actions if _is_positional(a)
                ),
                example=" ".join([prog, *_moved_forward(parser, given, refused)]),
            )
    return None


def missing_positionals(parser: argparse.ArgumentParser, given: Sequence[str]) -> bool:
    """Whether ``given`` leaves fewer values outside the options than the parser's positional
    arguments need (the sign that an option took them)."""
    need = sum(
        _fixed_count(a) or (1 if a.nargs == "+" else 0)
        for a in parser._actions
        if _is_positional(a)
    )
    _, free = _split(parser, given)
    return len(free) < need


def _split(
    parser: argparse.ArgumentParser, given: Sequence[str]
) -> tuple[dict[argparse.Action, list[int]], list[int]]:
    """Where argparse puts each value of ``given``: the indices each option of several
    values takes, and those left for the positional arguments."""
    taken: dict[argparse.Action, list[int]] = {}
    free: list[int] = []
    current: argparse.Action | None = None
    left = 0  # values still owed to an option of a fixed count
    for index, text in enumerate(given):
        if text == "--":
            free.extend(range(index + 1, len(given)))
            break
        if is_option(parser, text):
            action = option_action(parser, text)
            inline = "=" in text  # --at=0,0: the value is in the option
            many = action is not None and action.nargs in MANY and not inline
            current = action if many else None
            left = _fixed_count(action) if action is not None and not inline else 0
            if current is not None:
                taken.setdefault(current, [])
        elif left:
            left -= 1
        elif current is not None:
            taken[current].append(index)
        else:
            free.append(index)
    return taken, free


def _is_positional(action: argparse.Action) -> bool:
    return not action.option_strings and not isinstance(action, argparse._SubParsersAction)


def _fixed_count(action: argparse.Action) -> int:
    """Values an action takes when that number is fixed (0 for ``?``, ``*``, ``+``)."""
    if action.nargs is None:
        return 1
    if isinstance(action.nargs, int):
        return action.nargs
    return 0


def _moved_forward(
    parser: argparse.ArgumentParser, given: Sequence[str], moved: Sequence[int]
) -> list[str]:
    """``given`` with the values at ``moved`` put before the first option."""
    kept = [text for index, text in enumerate(given) if index not in moved]
    first = next((i for i, text in enumerate(kept) if is_option(parser, text)), len(kept))
    return [*kept[:first], *(given[index] for index in moved), *kept[first:]]
