"""A fixed, seeded set of planning problems in the shared cell (launch_specs/shared_cell.yaml).

Each arm's workspace over the table is split at the cell's midline (halfway between
the two bases): its *own* half and the *far* half, beyond the post and the walls.
A problem takes one arm (the other stays where it is, an obstacle) or both arms
(planned jointly, 14 joints) from a start to a goal on the other half of the table,
so the straight joint-space line runs into the post, the walls or the other arm.
Starts and goals are collision-free under the planning margin; whether the straight
line collides is measured, not assumed.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from cell_model import CellModel, Checker

from armfleet.messages import FloatArray

#: Where a tool counts as over the table [m]: within this of the midline along x,
#: within ``TABLE_HALF_WIDTH_M`` of the middle along y, and between these heights.
REACH_FROM_MIDLINE_M = (0.05, 0.35)
TABLE_HALF_WIDTH_M = 0.45
TOOL_HEIGHT_M = (0.2, 0.65)
#: A parked arm: its home with joint 1 turned to face away from the table [rad].
PARKED_JOINT1_RAD = 2.6
#: Samples drawn to fill one arm's pool of configurations of one half.
POOL_SAMPLES = 20_000


class Half(enum.Enum):
    """Which half of the table a tool is over, seen from its arm."""

    OWN = "own"
    FAR = "far"


@dataclass(frozen=True)
class CellProblem:
    """One planning problem.

    Attributes:
        index: position in the set.
        arms: arms planned, in the order of their joints in ``start`` and ``goal``.
        start: start positions of the planned joints [rad].
        goal: goal positions of the planned joints [rad].
        q_full: combined configuration of the whole cell at the start (fingers and
            arms not planned included).
        crossing: per planned arm, whether its goal is on the other half.
    """

    index: int
    arms: tuple[str, ...]
    start: FloatArray
    goal: FloatArray
    q_full: FloatArray
    crossing: tuple[bool, ...] = field(default=())

    @property
    def kind(self) -> str:
        """``"1 arm"`` or ``"2 arms"``."""
        return "1 arm" if len(self.arms) == 1 else f"{len(self.arms)} arms"


class ProblemSet:
    """Builds the problems of a cell with two arms.

    Args:
        cell: the cell's model (its arms: the first is one side, the second the other).
        checker: the checker whose margin starts and goals must respect.
        seed: seed of every random draw.
    """

    def __init__(self, cell: CellModel, checker: Checker, seed: int) -> None:
        self._cell = cell
        self._checker = checker
        self._rng = np.random.default_rng(seed)
        self._names = tuple(cell.arms)
        if len(self._names) != 2:
            raise ValueError(f"the cell needs two arms, got {len(self._names)}")
        model = cell.model
        self._data = model.createData()
        self._tools = {name: model.getFrameId(f"{name}_tool0") for name in self._names}
        bases = [model.frames[model.getFrameId(f"{name}_base_link")] for name in self._names]
        self._base_x = {
            name: float(frame.placement.translation[0])
            for name, frame in zip(self._names, bases, strict=True)
        }
        self._midline_x = sum(self._base_x.values()) / 2
        self._pools = {
            (name, half): self._pool(name, half)
            for name in self._names
            for half in (Half.OWN, Half.FAR)
        }

    @property
    def pool_sizes(self) -> dict[str, int]:
        """Configurations found per arm and half."""
        return {f"{name} {half.value}": len(pool) for (name, half), pool in self._pools.items()}

    def _parked(self) -> FloatArray:
        """The cell with every arm parked, facing away from the table."""
        q = self._cell.q
        for arm in self._cell.arms.values():
            home = q[list(arm.q_indices)]
            home[0] = PARKED_JOINT1_RAD
            q[list(arm.q_indices)] = home
        return q

    def _half(self, name: str, q: FloatArray) -> Half | None:
        """Which half the arm's tool is over at ``q``, or None if not over the table."""
        pin.forwardKinematics(self._cell.model, self._data, q)
        tool = pin.updateFramePlacement(self._cell.model, self._data, self._tools[name]).translation
        x, y, z = float(tool[0]), float(tool[1]), float(tool[2])
        toward = 1.0 if self._midline_x > self._base_x[name] else -1.0
        beyond = (x - self._midline_x) * toward  # > 0: past the midline, seen from the arm
        if abs(y) > TABLE_HALF_WIDTH_M or not TOOL_HEIGHT_M[0] <= z <= TOOL_HEIGHT_M[1]:
            return None
        near, far = REACH_FROM_MIDLINE_M
        if near <= -beyond <= far:
            return Half.OWN
        if near <= beyond <= far:
            return Half.FAR
        return None

    def _pool(self, name: str, half: Half) -> list[FloatArray]:
        """Configurations of ``name``, tool over ``half``, valid with the other arm parked."""
        arm = self._cell.arms[name]
        indices = list(arm.q_indices)
        q = self._parked()
        pool = []
        for _ in range(POOL_SAMPLES):
            values = self._rng.uniform(arm.lower, arm.upper)
            q[indices] = values
            if self._half(name, q) == half and not self._checker.collides(q):
                pool.append(values)
        if not pool:
            raise RuntimeError(f"no configuration of {name} reaches its {half.value} half")
        return pool

    def _draw(self, name: str, half: Half) -> FloatArray:
        pool = self._pools[(name, half)]
        return pool[int(self._rng.integers(len(pool)))]

    def problems(self, count: int) -> list[CellProblem]:
        """``count`` problems: half one arm (alternately each), half both arms jointly.

        One-arm problems cross the midline, one way or the other; the other arm stands
        on its own half. Two-arm problems cycle through both crossing, only the first
        crossing, only the second crossing (the other moving within its own half).
        """
        problems: list[CellProblem] = []
        patterns = ((True, True), (True, False), (False, True))
        for index in range(count):
            if index % 2 == 0:
                planned: Sequence[str] = (self._names[(index // 2) % 2],)
                crossing: tuple[bool, ...] = (True,)
            else:
                planned = self._names
                crossing = patterns[(index // 2) % len(patterns)]
            problems.append(self._problem(index, tuple(planned), crossing))
        return problems

    def _problem(
        self, index: int, planned: tuple[str, ...], crossing: tuple[bool, ...]
    ) -> CellProblem:
        cell = self._cell
        while True:
            q = cell.q
            starts, goals = [], []
            for name, crosses in zip(planned, crossing, strict=True):
                reverse = crosses and bool(self._rng.integers(2))  # far -> own, half the time
                first = Half.FAR if reverse else Half.OWN
                last = (Half.OWN if reverse else Half.FAR) if crosses else Half.OWN
                starts.append(self._draw(name, first))
                goals.append(self._draw(name, last))
            for name in cell.arms:
                if name not in planned:
                    q[list(cell.arms[name].q_indices)] = self._draw(name, Half.OWN)
            indices = cell.indices(planned)
            start, goal = np.concatenate(starts), np.concatenate(goals)
            q_goal = q.copy()
            q[indices], q_goal[indices] = start, goal
            if not self._checker.collides(q) and not self._checker.collides(q_goal):
                return CellProblem(index, planned, start, goal, q, crossing)
