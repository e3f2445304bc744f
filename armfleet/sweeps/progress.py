"""The progress line of a sweep: runs done, failed, runs per second and the time left.

The bar counts this call's runs. A resumed sweep says, once, in the bar's label, how many
runs the results file already held (``sweep (resumed, 40 runs already in the file)``);
a fresh one shows no such count.
"""

from __future__ import annotations

import sys

from tqdm import tqdm


class SweepProgress:
    """A tqdm bar on stderr, or nothing when ``enabled`` is False.

    On a terminal it redraws in place; into a file or pipe it writes a line every
    ``log_interval_s`` seconds.

    Args:
        total: the runs this call makes.
        done_before: the runs a resumed sweep's results file already held.
    """

    def __init__(self, total: int, done_before: int, enabled: bool, log_interval_s: float = 10.0):
        self.failed = 0
        self._bar: tqdm[None] | None = None
        if enabled:
            terminal = sys.stderr.isatty()
            self._bar = tqdm(
                total=total,
                unit="run",
                desc=label(done_before),
                file=sys.stderr,
                dynamic_ncols=True,
                mininterval=0.2 if terminal else log_interval_s,
                maxinterval=max(10.0, log_interval_s),
                postfix={"failed": 0},
            )

    def update(self, runs: int, failed: int) -> None:
        self.failed += failed
        if self._bar is not None:
            if failed:
                self._bar.set_postfix(failed=self.failed, refresh=False)
            self._bar.update(runs)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def label(done_before: int) -> str:
    """The bar's label: ``sweep``, and for a resumed sweep the runs it had before."""
    if done_before == 0:
        return "sweep"
    return f"sweep (resumed, {done_before} runs already in the file)"
