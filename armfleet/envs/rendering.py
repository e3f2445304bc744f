"""Images of a world for videos: PyBullet's software renderer (``ER_TINY_RENDERER``) on the
world's own DIRECT client, so no display and no GPU are needed.

Arms are drawn from their collision shapes (the world loads them without visual shapes),
in grey; objects in grey too. The camera looks at the middle of the arms' bases from a
distance that grows with how far apart they stand.
"""

from __future__ import annotations

import enum

import numpy as np
import numpy.typing as npt
import pybullet as p

from armfleet.envs.errors import InvalidOption
from armfleet.world import World

#: Width and height of a frame [pixels] unless asked otherwise.
DEFAULT_SIZE = (320, 240)
#: Vertical field of view [deg].
FIELD_OF_VIEW_DEG = 50.0


class RenderMode(enum.Enum):
    """Gymnasium's render modes that the environments support."""

    RGB_ARRAY = "rgb_array"
    HUMAN = "human"

    @classmethod
    def parse(cls, value: object) -> RenderMode | None:
        if value is None or isinstance(value, RenderMode):
            return value
        for mode in cls:
            if value == mode.value:
                return mode
        raise InvalidOption("render_mode", value, ["None", *(mode.value for mode in cls)])


def check_size(size: object) -> tuple[int, int]:
    """``size`` as (width, height) in pixels, each in [16, 2048]."""
    valid = "(width, height) in pixels, each a whole number in [16, 2048]"
    if not isinstance(size, tuple | list) or len(size) != 2:
        raise InvalidOption("render_size", size, valid)
    if not all(isinstance(v, int) and not isinstance(v, bool) and 16 <= v <= 2048 for v in size):
        raise InvalidOption("render_size", size, valid)
    return int(size[0]), int(size[1])


def render_rgb(world: World, size: tuple[int, int] = DEFAULT_SIZE) -> npt.NDArray[np.uint8]:
    """An RGB image (height, width, 3) of ``world`` as it is now."""
    width, height = size
    bases = np.array([[arm.pose.x, arm.pose.y] for arm in world.arms.values()] or [[0.0, 0.0]])
    centre = [*bases.mean(axis=0), 0.3]
    spread = float(np.ptp(bases, axis=0).max()) if len(bases) > 1 else 0.0
    distance = 1.6 + 0.9 * spread
    eye = [centre[0] + 0.55 * distance, centre[1] - 0.75 * distance, 0.3 + 0.6 * distance]
    client = world.physics_client
    view = p.computeViewMatrix(eye, centre, [0, 0, 1], physicsClientId=client)
    projection = p.computeProjectionMatrixFOV(
        FIELD_OF_VIEW_DEG, width / height, 0.05, 50.0, physicsClientId=client
    )
    _, _, rgba, _, _ = p.getCameraImage(
        width, height, view, projection, renderer=p.ER_TINY_RENDERER, physicsClientId=client
    )
    image = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
    return np.ascontiguousarray(image[:, :, :3])
