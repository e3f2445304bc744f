"""What an arm's action is (its space) and how one is checked before anything moves.

Each arm's action is a ``Dict``: one arm entry, named after the action kind, and, for an
arm with fingers in a task that uses them (not Reach), ``"gripper"``. Every entry is a
float32 ``Box``:

- ``"joint_positions"``: target positions of the arm's joints (``arm.joint_names``),
  bounded by the joint limits [rad];
- ``"joint_deltas"``: a change of the previous target, at most ``max_joint_step_rad``
  per joint per control period [rad];
- ``"tool_delta"``: (dx, dy, dz, droll, dpitch, dyaw) of the previous tool0 target, along
  and about the **world** axes through tool0's origin, at most ``max_tool_step_m`` [m] and
  ``max_tool_step_rad`` [rad] per control period;
- ``"tool_servo"``: (dx, dy, dz) of tool0 from where it *is* (measured), along the world
  axes, at most ``max_tool_step_m`` per axis per control period [m]; its orientation is
  held at the episode's start (as panda-gym's end-effector displacements). The arms then
  run a responsive position controller (:mod:`armfleet.envs.servo_controller`), so that
  they follow such a command within a few control periods;
- ``"gripper"``: shape (1,), in [0, 1]: above 0.5 closes (grasp), otherwise opens.

A value that is not finite, or an entry of the wrong shape, or a missing or unknown arm
or entry, is refused with :class:`~armfleet.envs.errors.InvalidAction` before any arm is
touched. Finite values outside the Box are clipped to it (as Gymnasium's ``ClipAction``
would); the step's ``info["clipped"]`` names them.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from armfleet.arms.arm import Arm
from armfleet.checks.real_numbers import all_real
from armfleet.envs.choices import choose
from armfleet.envs.errors import InvalidAction, InvalidOption
from armfleet.kinematics.continuous_joints import one_turn_bounds
from armfleet.messages import FloatArray

GRIPPER = "gripper"
#: A gripper value above this closes the fingers.
GRIPPER_CLOSE_ABOVE = 0.5


class ActionKind(enum.Enum):
    """What an arm's action commands (chosen when the environment is made)."""

    JOINT_POSITIONS = "joint_positions"
    JOINT_DELTAS = "joint_deltas"
    TOOL_DELTA = "tool_delta"
    TOOL_SERVO = "tool_servo"

    @classmethod
    def parse(cls, value: object) -> ActionKind:
        """``value`` as a kind (the enum or its name); InvalidOption lists the kinds."""
        return choose(cls, value, "action_kind")


@dataclass(frozen=True)
class StepLimits:
    """Largest change one action asks for, per control period.

    Attributes:
        joint_rad: per joint, of ``joint_deltas`` [rad].
        tool_m: per axis, of the position part of ``tool_delta`` [m].
        tool_rad: per axis, of the rotation part of ``tool_delta`` [rad].
    """

    joint_rad: float = 0.05
    tool_m: float = 0.02
    tool_rad: float = 0.1

    def __post_init__(self) -> None:
        for name, value, high in (
            ("max_joint_step_rad", self.joint_rad, 1.0),
            ("max_tool_step_m", self.tool_m, 0.5),
            ("max_tool_step_rad", self.tool_rad, 1.0),
        ):
            if not all_real([value]) or not 0 < value <= high or not math.isfinite(value):
                raise InvalidOption(name, value, f"a number in (0, {high}]")


def arm_action_space(
    arm: Arm, kind: ActionKind, limits: StepLimits, *, gripper: bool = True
) -> spaces.Dict:
    """The action space of ``arm`` for ``kind``; with a ``gripper`` entry if the arm has
    fingers and ``gripper`` is set."""
    count = len(arm.joint_names)
    if kind is ActionKind.JOINT_POSITIONS:
        lower, upper = one_turn_bounds(*arm.joint_limits)  # a continuous joint: one turn
        main = spaces.Box(lower.astype(np.float32), upper.astype(np.float32), dtype=np.float32)
    elif kind is ActionKind.JOINT_DELTAS:
        main = spaces.Box(-limits.joint_rad, limits.joint_rad, (count,), dtype=np.float32)
    elif kind is ActionKind.TOOL_SERVO:
        main = spaces.Box(-limits.tool_m, limits.tool_m, (3,), dtype=np.float32)
    else:
        bound = np.array([limits.tool_m] * 3 + [limits.tool_rad] * 3, dtype=np.float32)
        main = spaces.Box(-bound, bound, dtype=np.float32)
    entries: dict[str, spaces.Space[object]] = {kind.value: main}
    if gripper and arm.has_gripper:
        entries[GRIPPER] = spaces.Box(0.0, 1.0, (1,), dtype=np.float32)
    return spaces.Dict(entries)


def check_action(
    space: spaces.Dict, action: object
) -> tuple[dict[str, dict[str, FloatArray]], list[str]]:
    """``action`` for all arms as float64 arrays, clipped into ``space``, and the
    ``"arm.entry"`` names of what was clipped.

    Raises:
        InvalidAction: not a mapping of every arm (and nothing else) to its entries,
            a wrong shape, or a value that is not a finite number.
    """
    arms = list(space.spaces)
    if not isinstance(action, Mapping) or set(action) != set(arms):
        given = sorted(map(str, action)) if isinstance(action, Mapping) else type(action).__name__
        raise InvalidAction("", "", f"got {given}", f"a dict with one entry per arm: {arms}")
    checked: dict[str, dict[str, FloatArray]] = {}
    clipped: list[str] = []
    for name in arms:
        arm_space = space.spaces[name]
        assert isinstance(arm_space, spaces.Dict)
        values, arm_clipped = check_arm_action(name, arm_space, action[name])
        checked[name] = values
        clipped += arm_clipped
    return checked, clipped


def check_arm_action(
    arm: str, space: spaces.Dict, action: object
) -> tuple[dict[str, FloatArray], list[str]]:
    """One arm's action, as :func:`check_action` checks it."""
    fields = list(space.spaces)
    if not isinstance(action, Mapping) or set(action) != set(fields):
        given = sorted(map(str, action)) if isinstance(action, Mapping) else type(action).__name__
        raise InvalidAction(arm, "", f"got {given}", f"a dict with the entries {fields}")
    values: dict[str, FloatArray] = {}
    clipped: list[str] = []
    for field in fields:
        box = space.spaces[field]
        assert isinstance(box, spaces.Box)
        raw = action[field]
        try:
            raw_array = np.asarray(raw)
        except (TypeError, ValueError):  # ragged
            raise InvalidAction(arm, field, f"got {type(raw).__name__}", _valid(box)) from None
        if raw_array.dtype.kind not in "fiu":  # not text, bool, None or objects
            raise InvalidAction(arm, field, f"got {raw_array.dtype} values", _valid(box))
        array = raw_array.astype(np.float64)
        if array.shape != box.shape:
            raise InvalidAction(arm, field, f"got shape {array.shape}", _valid(box))
        bad = np.flatnonzero(~np.isfinite(array))
        if bad.size:
            raise InvalidAction(arm, field, f"element {bad[0]} is {array[bad[0]]}", _valid(box))
        low, high = box.low.astype(np.float64), box.high.astype(np.float64)
        inside = np.clip(array, low, high)
        if not np.array_equal(inside, array):
            clipped.append(f"{arm}.{field}")
        values[field] = inside
    return values, clipped


def _valid(box: spaces.Box) -> str:
    """What a value of ``box`` is, for an error message."""
    return f"{box.shape[0]} finite numbers in [{_bounds(box)}]"


def _bounds(box: spaces.Box) -> str:
    low, high = np.unique(box.low), np.unique(box.high)
    if low.size == 1 and high.size == 1:
        return f"{low[0]:g}, {high[0]:g}"
    return "the bounds of the arm's action space (its joint limits)"
