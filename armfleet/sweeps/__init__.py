"""Sweeps: a scenario (a launch spec and a task) run for many seeds on Ray, one row per run.

>>> import armfleet
>>> result = armfleet.sweep("reach", runs=40, output="reach.parquet")
>>> result.table.to_pandas().groupby("task.arm_count").reached_fraction.mean()

See docs/sweeps.md: how to write a task and a randomization, local and cluster use.

Rule: a front end (the ``sweeps`` extra: Ray, pyarrow); imports the scenarios, the
world and the core below; nothing but the CLI and the public API (on first use) import it.
"""

from armfleet.checks.extras import require_extra

require_extra("Sweeps", "sweeps", "ray", "pyarrow")


from armfleet.sweeps.definition import SweepDefinition, load_sweep, shipped_scenarios
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.results_file import read_results
from armfleet.sweeps.run import run_seed
from armfleet.sweeps.sweep import SweepInterrupted, SweepResult, sweep

__all__ = [
    "SweepDefinition",
    "SweepError",
    "SweepInterrupted",
    "SweepResult",
    "load_sweep",
    "read_results",
    "run_seed",
    "shipped_scenarios",
    "sweep",
]
