"""The flat form of an environment's spaces (``flat=True``), as Stable-Baselines3 and most
reinforcement-learning libraries take them.

- **Actions**: one float32 ``Box`` in [-1, 1]: every arm's entries, one after the other
  (arms and entries in the order of the ``Dict`` space, ``Dict``'s sorted keys), each
  value mapped affinely onto its entry's range (-1: the entry's low bound, 1: its high
  bound, 0: the middle; a ``joint_deltas`` value of 0 keeps the target). A flat action
  becomes the ``Dict`` action and is then checked as every action is
  (:mod:`armfleet.envs.actions`): a wrong shape or a value that is not finite is refused;
  values outside [-1, 1] are clipped, and ``info["clipped"]`` names their entries.
- **Observations**: Gymnasium's ``flatten`` of the ``Dict`` observation, a float32 ``Box``
  (``flatten_space``), in the same order.

:meth:`FlatSpaces.entries` lists what each slice of the flat vectors is.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from armfleet.envs.errors import InvalidAction
from armfleet.messages import FloatArray


class FlatSpaces:
    """Maps between the ``Dict`` spaces of an environment and their flat forms.

    Args:
        actions: the environment's ``Dict`` of arms, each a ``Dict`` of ``Box`` entries.
        observations: its ``Dict`` of observations.
    """

    def __init__(self, actions: spaces.Dict, observations: spaces.Dict) -> None:
        self._dict_observations = observations
        #: (arm, entry, slice of the flat action, low, high) per action entry.
        self._action_entries: list[tuple[str, str, slice, FloatArray, FloatArray]] = []
        start = 0
        for arm, arm_space in actions.spaces.items():
            assert isinstance(arm_space, spaces.Dict)
            for entry, box in arm_space.spaces.items():
                assert isinstance(box, spaces.Box)
                size = int(np.prod(box.shape))
                low = box.low.astype(np.float64).ravel()
                high = box.high.astype(np.float64).ravel()
                self._action_entries.append((arm, entry, slice(start, start + size), low, high))
                start += size
        self.action_space = spaces.Box(-1.0, 1.0, (start,), dtype=np.float32)
        flat = spaces.flatten_space(observations)
        assert isinstance(flat, spaces.Box)
        self.observation_space = flat

    def entries(self) -> dict[str, slice]:
        """``"arm.entry"`` -> its slice of the flat action."""
        return {f"{arm}.{entry}": part for arm, entry, part, _, _ in self._action_entries}

    def action(self, flat: object) -> dict[str, dict[str, FloatArray]]:
        """The ``Dict`` action of a flat one (values outside [-1, 1] map outside the
        entries' ranges, and are clipped as any action is).

        Raises:
            InvalidAction: not numbers, or not of the flat space's shape.
        """
        shape = self.action_space.shape
        valid = f"{shape[0]} finite numbers in [-1, 1]"
        try:
            array = np.asarray(flat)
        except (TypeError, ValueError):  # ragged
            raise InvalidAction("", "", f"got {type(flat).__name__}", valid) from None
        if array.dtype.kind not in "fiu":
            raise InvalidAction("", "", f"got {array.dtype} values", valid)
        if array.shape != shape:
            raise InvalidAction("", "", f"got shape {array.shape}", valid)
        values = array.astype(np.float64)
        action: dict[str, dict[str, FloatArray]] = {}
        for arm, entry, part, low, high in self._action_entries:
            value = values[part]
            scaled = low + (value + 1.0) * 0.5 * (high - low)
            # [-1, 1] lands inside the range despite rounding; the rest is clipped later.
            inside = np.abs(value) <= 1.0
            action.setdefault(arm, {})[entry] = np.where(inside, np.clip(scaled, low, high), scaled)
        return action

    def observation(self, observation: dict[str, Any]) -> FloatArray:
        """The flat observation of a ``Dict`` one (float32)."""
        flat = np.asarray(spaces.flatten(self._dict_observations, observation))
        return flat.astype(np.float32)
