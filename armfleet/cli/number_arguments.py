"""Argparse ``type=`` checks for the numbers of every command (timeouts, durations, step
counts, ports, speeds), built from the ranges of :mod:`armfleet.checks.number_ranges`.

A value outside its range stops the command while its arguments are parsed, before it
connects to a world or sends anything; the one error line names the argument and the
valid range, e.g. ``argument --wait-timeout: 'nan' is invalid; give seconds in [0, 600]``.
"""

from __future__ import annotations

import argparse

from armfleet.checks.number_ranges import (
    PORT,
    PORT_OR_FREE,
    REPLAY_SPEED,
    REQUEST_TIMEOUT_S,
    RUN_DURATION_S,
    STEP_COUNT,
    WAIT_TIMEOUT_S,
    NumberRange,
)


class NumberArgument:
    """An argparse ``type=`` that reads a number in ``valid`` or refuses it in one line.

    The help of an argument of this type ends with its range (see
    :class:`armfleet.cli.parser.OneLineParser`), taken from ``valid``.

    Attributes:
        valid: the range of the number.
    """

    def __init__(self, valid: NumberRange) -> None:
        self.valid = valid
        # argparse names the type by it in some messages.
        self.__name__ = valid.meaning

    def __call__(self, text: str) -> float:
        try:
            return self.valid.parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None


class IntegerArgument(NumberArgument):
    """Like :class:`NumberArgument`, for a range of integers."""

    def __call__(self, text: str) -> int:
        return int(super().__call__(text))


def number_in(valid: NumberRange) -> NumberArgument:
    """An argparse ``type=`` that reads a number in ``valid`` or refuses it in one line."""
    return NumberArgument(valid)


def integer_in(valid: NumberRange) -> IntegerArgument:
    """Like :func:`number_in`, for a range of integers."""
    return IntegerArgument(valid)


#: ``--timeout``: a wait for the world's answer [s].
request_timeout = number_in(REQUEST_TIMEOUT_S)
#: ``--wait-timeout``: a wait for a motion to finish [s].
wait_timeout = number_in(WAIT_TIMEOUT_S)
#: ``--duration``: simulated seconds of a run.
run_duration = number_in(RUN_DURATION_S)
#: ``step N``.
step_count = integer_in(STEP_COUNT)
#: ``--viewer-port``.
port = integer_in(PORT)
#: ``--api-port`` (0: a free one).
port_or_free = integer_in(PORT_OR_FREE)
#: ``replay --speed``.
replay_speed = number_in(REPLAY_SPEED)
