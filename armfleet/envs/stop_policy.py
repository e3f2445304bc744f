"""What an environment does when an arm stops on a contact (a protective stop) or faults."""

from __future__ import annotations

import enum

from armfleet.envs.choices import choose


class StopPolicy(enum.Enum):
    """What happens after a step in which an arm is in protective stop or in error.

    Either way the step's ``info["stopped"]`` names the arms.

    Attributes:
        TERMINATE: the episode ends (``terminated=True``): touching the floor, a table or
            another arm is a failure, as on a real cell.
        RESET: the arms are reset (``arm.reset()``: the stop is lifted, the contact
            excused) and their targets taken where they stopped; the episode goes on.
    """

    TERMINATE = "terminate"
    RESET = "reset"

    @classmethod
    def parse(cls, value: object) -> StopPolicy:
        return choose(cls, value, "on_stop")
