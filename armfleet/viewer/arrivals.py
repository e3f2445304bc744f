"""The arms a viewer awaits: where the camera looks before their meshes come, and the
page's loading line while they come.

A launch knows where its arms will stand before the first one comes up (the spec's
spawn poses). Framing each arm only once it was shown put the first arm, half built,
at the edge of the page for the 10-15 s its meshes take in a software-rendered page,
then jumped (issue 28). Now the camera frames every awaited arm from the first frame:
until an arm is shown it counts as a box around its base, about an arm at rest (a
Panda at home spans -0.22..0.31 m along x and 0.70 m up from its base), and an arm
about to be shown counts as its frames where it stands, before any mesh is sent.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence

import numpy as np

from armfleet.viewer.errors import ViewerError
from armfleet.viewer.scene import Box

#: Half-width along x and y [m] and height [m] of the box an awaited arm is framed as.
AWAITED_HALF_WIDTH_M = 0.35
AWAITED_HEIGHT_M = 0.75


def awaited_box(position: Sequence[float]) -> Box:
    """The box [m] framed for an arm whose base will stand at ``position`` (x, y, z)."""
    base = np.asarray(position, dtype=float)
    reach = np.array([AWAITED_HALF_WIDTH_M, AWAITED_HALF_WIDTH_M, 0.0])
    return base - reach, base + reach + np.array([0.0, 0.0, AWAITED_HEIGHT_M])


def base_positions(positions: Mapping[str, Sequence[float]]) -> dict[str, tuple[float, ...]]:
    """``positions`` checked: arm name -> base position (x, y, z) [m], finite numbers.

    Raises:
        ViewerError: not a mapping of names to three finite numbers.
    """
    if not isinstance(positions, Mapping):
        raise ViewerError(
            f"expected arms: give a mapping of arm name to base (x, y, z) in m, "
            f"got {type(positions).__name__}"
        )
    checked: dict[str, tuple[float, ...]] = {}
    for name, position in positions.items():
        try:
            values = tuple(float(v) for v in position)
        except (TypeError, ValueError):
            values = ()
        if not isinstance(name, str) or len(values) != 3 or not all(map(math.isfinite, values)):
            raise ViewerError(
                f"expected arm {name!r}: give its base as three finite numbers (x, y, z) "
                f"in m, got {position!r}"
            )
        checked[name] = values
    return checked


class Arrivals:
    """The arms awaited or being loaded, by name, as boxes; and the loading line."""

    def __init__(self) -> None:
        self._awaited: dict[str, Box] = {}
        self._loading: str | None = None

    def await_arms(self, positions: Mapping[str, Sequence[float]]) -> None:
        """Await the arms of ``positions`` (name -> base x, y, z [m]) instead of any before."""
        self._awaited = {name: awaited_box(p) for name, p in base_positions(positions).items()}

    def arriving(self, name: str, box: Box) -> None:
        """Arm ``name`` is being loaded; it stands in ``box`` [m]."""
        self._awaited[name] = box
        self._loading = name

    def arrived(self, name: str) -> None:
        """Arm ``name`` is shown, could not be shown, or went away."""
        self._awaited.pop(name, None)
        if self._loading == name:
            self._loading = None

    def boxes(self, shown: Collection[str]) -> list[Box]:
        """The boxes of the arms awaited and not in ``shown``."""
        return [box for name, box in self._awaited.items() if name not in shown]

    def line(self, shown: Collection[str]) -> str:
        """The page's loading line, given the arms ``shown`` now; empty when none is awaited."""
        pending = [name for name in self._awaited if name not in shown]
        if not pending:
            return ""
        ready = [name for name in shown if name not in self._awaited]
        total = len(ready) + len(pending)
        if self._loading is not None:
            return f"loading the meshes of {self._loading} (arm {len(ready) + 1} of {total})…"
        return f"{len(ready)} of {total} arms shown; waiting for {', '.join(pending)}…"
