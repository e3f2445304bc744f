"""The ranges of the numbers users give commands and services: timeouts, run durations,
step counts, ports, replay speeds, world coordinates and pose angles.

One place for each range, so that the command line (its argument checks), the live
API (the server's request checks) and the Python client refuse the same values, in
the same words. A value is valid when it is a finite real number inside its closed
range (an integer where the range says so); ``nan``, ``inf`` and ``1e308`` never are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from armfleet.checks.real_numbers import is_real
from armfleet.errors import InvalidNumber


@dataclass(frozen=True)
class NumberRange:
    """A closed range ``[low, high]`` of a number a user gives.

    Attributes:
        low, high: inclusive bounds.
        meaning: what the number is, with its unit, for messages (``"seconds"``,
            ``"steps"``).
        integer: only whole numbers are valid.
    """

    low: float
    high: float
    meaning: str
    integer: bool = False

    @property
    def valid(self) -> str:
        """What a valid value is, e.g. ``seconds in [0, 600]`` or ``steps, an integer in
        1..100000``."""
        if self.integer:
            return f"{self.meaning}, an integer in {self.low:.0f}..{self.high:.0f}"
        return f"{self.meaning} in [{_shown(self.low)}, {_shown(self.high)}]"

    def contains(self, value: object) -> bool:
        """Whether ``value`` is a finite real number in the range (a whole one if
        :attr:`integer`); text, bool and None are not."""
        if not is_real(value):
            return False
        number = float(value)  # type: ignore[arg-type]  # is_real checked it
        if not (math.isfinite(number) and self.low <= number <= self.high):
            return False
        return not self.integer or number.is_integer()

    def check(self, value: object, argument: str) -> float:
        """``value`` as a float if :meth:`contains` it.

        Args:
            value: what the user gave.
            argument: its name in the message (``"timeout"``, ``"step count"``).

        Raises:
            InvalidNumber: naming ``argument``, the value and the valid range.
        """
        if not self.contains(value):
            raise InvalidNumber(argument, value, self.valid)
        return float(value)  # type: ignore[arg-type]  # contains() checked it

    def parse(self, text: str) -> float:
        """A command-line value as a number in the range (int-valued if :attr:`integer`).

        Raises:
            ValueError: not a number, or outside the range; the message says what is valid.
        """
        try:
            value = int(text, 10) if self.integer else float(text)
        except ValueError:
            kind = "an integer" if self.integer else "a number"
            raise ValueError(f"{text!r} is not {kind}; give {self.valid}") from None
        if not self.contains(value):
            raise ValueError(f"{text!r} is invalid; give {self.valid}")
        return value + 0.0 if not self.integer else value  # -0.0 reads as 0.0


def _shown(bound: float) -> str:
    """``1000000`` rather than ``1e+06``; ``0.001`` as is."""
    return f"{bound:.0f}" if float(bound).is_integer() and abs(bound) < 1e9 else f"{bound:g}"


#: A wait for the world's answer to one request, and the longest a request may wait
#: in the world's queue, whatever the client asks [s].
REQUEST_TIMEOUT_S = NumberRange(0.001, 600.0, "seconds")
#: A wait for an arm (or a gripper) to finish its motion [s].
WAIT_TIMEOUT_S = NumberRange(0.0, 600.0, "seconds")
#: Simulated time a command-line run lasts (longer: no --duration, run until Ctrl-C) [s].
RUN_DURATION_S = NumberRange(0.0, 1e6, "seconds")
#: Steps one ``step`` request advances a paused world.
STEP_COUNT = NumberRange(1, 100_000, "steps", integer=True)
#: A TCP port given by the user.
PORT = NumberRange(1, 65535, "a TCP port", integer=True)
#: A TCP port, or 0 for a free one.
PORT_OR_FREE = NumberRange(0, 65535, "a TCP port (0: a free one)", integer=True)
#: ``--foxglove-rate``: instants of the streamed topics sent per simulated second [Hz]; at
#: or above the step rate (1,000 Hz at the default 1 ms) every step goes out.
FOXGLOVE_RATE_HZ = NumberRange(0.1, 1e6, "a rate in Hz of simulated time")
#: ... when not given: a display's rate, a tenth of the steps at the default 1 ms.
DEFAULT_FOXGLOVE_RATE_HZ = 100.0
#: A coordinate of a position in the world (an arm's base, an object, a pose goal) [m]:
#: room for any cell. Far beyond it the whole world slows down: one arm spawned at
#: x = 1e308 m cut a shared world's real-time factor from 1.00 to about 0.2.
#: A ROS 2 domain id (Fast DDS on Linux: 0..232).
ROS_DOMAIN_ID = NumberRange(0, 232, "a ROS domain id", integer=True)
#: Instants of the ROS 2 topics per simulated second, and its default (a controller
#: manager's usual update rate).
ROS_RATE_HZ = NumberRange(0.1, 1000.0, "a rate in Hz of simulated time")
DEFAULT_ROS_RATE_HZ = 100.0
WORLD_COORDINATE_M = NumberRange(-1000.0, 1000.0, "metres")
#: An angle of a pose given in degrees (roll, pitch, yaw) [deg].
ANGLE_DEG = NumberRange(-360.0, 360.0, "degrees")
#: Replay speed, times real time.
REPLAY_SPEED = NumberRange(0.001, 1000.0, "a factor (times real time)")

#: The margin a collision-free plan keeps between different bodies [m]: above 0 (a
#: plan is proven clear by it), at most half a metre (more leaves no room to move).
CLEARANCE_M = NumberRange(0.001, 0.5, "metres")
#: The time budget of one planning request [s].
PLANNING_TIMEOUT_S = NumberRange(0.001, 60.0, "seconds")
#: The work budget of one planning request, instead of its time: RRT-Connect iterations
#: (one sample and one extension of each tree each). A Panda's request in the shared
#: cell needs tens at the median; a million is minutes of work.
PLANNING_BUDGET = NumberRange(1, 1_000_000, "planner iterations", integer=True)

# Sweeps (here, not in armfleet.sweeps, so that the CLI checks them without loading Ray).
#: Most runs of one sweep.
MAX_SWEEP_RUNS = 10_000_000
#: Runs of a sweep.
SWEEP_RUNS = NumberRange(1, MAX_SWEEP_RUNS, "runs", integer=True)
#: Runs at once.
SWEEP_WORKERS = NumberRange(1, 100_000, "workers", integer=True)
#: One run's wall-time limit [s].
SWEEP_RUN_TIMEOUT_S = NumberRange(0.001, 86_400, "seconds")
#: The first run's seed.
SWEEP_BASE_SEED = NumberRange(0, 2**62, "seed", integer=True)
#: Runs per Ray task.
SWEEP_BATCH = NumberRange(1, 10_000, "runs per task", integer=True)
