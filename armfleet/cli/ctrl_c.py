"""Ctrl-C reaches a command that runs until it: a process started in the background by a
shell, or by a pytest-xdist worker, inherits SIGINT ignored, and Python then leaves it
ignored, so ``kill -INT`` (and the Ctrl-C its caller forwards) would do nothing."""

from __future__ import annotations

import signal


def let_ctrl_c_stop() -> None:
    """Make SIGINT raise KeyboardInterrupt in this process, whatever it inherited."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
