"""Joint positions of every arm (and the pose of every scene object) at a fixed rate of
simulated time, for the replay.

Recording stores one copy of each arm's joint positions per frame (9 floats
for a Panda: 10 arms at 30 frames/s take ~80 MB per simulated hour).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from armfleet.messages import FloatArray

DEFAULT_FPS = 30.0


@dataclass
class Track:
    """The recorded positions of one arm.

    Attributes:
        first_frame: frame index of ``positions[0]``.
        positions: joint positions (model order) per frame.
    """

    first_frame: int
    positions: list[FloatArray] = field(default_factory=list)

    def array(self) -> FloatArray:
        """Positions as a frames x joints array."""
        return np.array(self.positions, dtype=float)


class Recorder:
    """Samples arms at ``fps`` frames per second of simulated time.

    Args:
        fps: frames per simulated second.
    """

    def __init__(self, fps: float = DEFAULT_FPS) -> None:
        self.fps = fps
        self._frame = 0
        #: Simulated time of the next frame [s]; a caller checks it before :meth:`record`.
        self.next_time_s = 0.0
        self._tracks: dict[str, Track] = {}

    @property
    def frames(self) -> int:
        """Frames recorded so far."""
        return self._frame

    @property
    def tracks(self) -> dict[str, Track]:
        return dict(self._tracks)

    def add(self, name: str) -> None:
        """Record arm ``name`` from the next frame on."""
        self._tracks[name] = Track(self._frame)

    def remove(self, name: str) -> None:
        self._tracks.pop(name, None)

    def record(self, time_s: float, positions: Mapping[str, FloatArray]) -> None:
        """Store every frame due by ``time_s`` (simulated) from ``positions`` by arm."""
        while time_s >= self.next_time_s:
            for name, track in self._tracks.items():
                track.positions.append(positions[name].copy())
            self._frame += 1
            self.next_time_s = self._frame / self.fps
