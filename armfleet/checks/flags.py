"""The one rule for a yes/no argument a user gave: a real bool.

Python reads anything as a condition: ``move_to_pose(goal, linear="no")`` would
move in a straight line, ``World(viewer="False")`` would start a viewer, and
``1`` or ``None`` pass unnoticed. Every public keyword that is a flag (``linear``,
``realtime``, ``viewer``, ``latch``, the viewer's ``show_frames`` and
``show_targets``, the live-API client's ``linear``, ``serve``'s ``register``) goes
through :func:`flag`, so
all refuse the same things: text, numbers, None and anything else not a bool.
A NumPy bool is a bool.
"""

from __future__ import annotations

import numpy as np

from armfleet.errors import InvalidFlag


def flag(value: object, argument: str) -> bool:
    """``value`` as a Python bool if it is ``True``/``False`` (or a NumPy bool).

    Args:
        value: what the user gave.
        argument: its name in the message (``"linear"``).

    Raises:
        InvalidFlag: naming ``argument`` and the value, asking for True or False.
    """
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise InvalidFlag(argument, value)
