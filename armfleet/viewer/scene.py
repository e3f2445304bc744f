"""The viewer's stage: background, a ground grid under the arms and a camera framing them.

MeshCat 0.3's orbit controls always turn around the page's origin and offer no
command to move that centre, so the stage moves the world instead: everything
armfleet draws lives under ``/meshcat``, whose transform puts the middle of
the fleet at the page's origin. Poses under ``/meshcat`` stay world poses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

#: Background gradient, RGB in [0, 1] (MeshCat scales them to bytes).
BACKGROUND_TOP = (0.77, 0.82, 0.87)
BACKGROUND_BOTTOM = (0.32, 0.37, 0.44)
#: Ground grid: cell size, margin around the arms and line colour.
GRID_CELL_M = 0.25
GRID_MARGIN_M = 1.0
GRID_COLOR = 0x30343A
#: Vertical field of view of MeshCat's default camera [deg].
CAMERA_FOV_DEG = 75.0
#: Direction from the scene centre to the camera (world frame, z up).
CAMERA_DIRECTION = np.array([0.35, -1.0, 0.55])
#: Length of the world axes drawn at the origin [m].
ORIGIN_AXES_M = 0.3
#: Room kept around the arms' frame origins for their meshes [m].
MESH_MARGIN_M = 0.15
#: Extent framed when there is no arm yet [m].
EMPTY_SCENE = (np.array([-0.5, -0.5, 0.0]), np.array([0.5, 0.5, 1.0]))

Vector = npt.NDArray[np.float64]
Box = tuple[Vector, Vector]


def scene_box(bounds: Sequence[Box]) -> Box:
    """The box holding every arm's ``(min, max)`` corners, their meshes and the floor."""
    if not bounds:
        return EMPTY_SCENE
    lower = np.min([b[0] for b in bounds], axis=0) - MESH_MARGIN_M
    upper = np.max([b[1] for b in bounds], axis=0) + MESH_MARGIN_M
    return np.minimum(lower, [np.inf, np.inf, 0.0]), upper


def camera_placement(box: Box) -> tuple[Vector, Vector]:
    """(target, camera position) in the world [m] that keep ``box`` in view."""
    lower, upper = box
    target = 0.5 * (lower + upper)
    radius = 0.5 * float(np.linalg.norm(upper - lower))
    distance = radius / math.tan(math.radians(CAMERA_FOV_DEG) / 2)
    direction = CAMERA_DIRECTION / np.linalg.norm(CAMERA_DIRECTION)
    return target, target + distance * direction


def grid_lines(box: Box) -> npt.NDArray[np.float32]:
    """End points (3 x 2n) of a ground grid covering ``box`` plus a margin, on cell lines."""
    lower = np.floor((box[0][:2] - GRID_MARGIN_M) / GRID_CELL_M) * GRID_CELL_M
    upper = np.ceil((box[1][:2] + GRID_MARGIN_M) / GRID_CELL_M) * GRID_CELL_M
    xs = np.arange(lower[0], upper[0] + GRID_CELL_M / 2, GRID_CELL_M)
    ys = np.arange(lower[1], upper[1] + GRID_CELL_M / 2, GRID_CELL_M)
    points = [((x, lower[1]), (x, upper[1])) for x in xs]
    points += [((lower[0], y), (upper[0], y)) for y in ys]
    flat = np.array(points, dtype=np.float32).reshape(-1, 2)
    return np.vstack([flat.T, np.zeros((1, len(flat)), dtype=np.float32)])


class Stage:
    """Background, ground grid and camera of one viewer.

    Args:
        visualizer: the viewer's ``meshcat.Visualizer``.
    """

    def __init__(self, visualizer: Any) -> None:
        self._visualizer = visualizer
        self._grid: npt.NDArray[np.float32] | None = None
        background = visualizer["/Background"]
        background.set_property("top_color", list(BACKGROUND_TOP))
        background.set_property("bottom_color", list(BACKGROUND_BOTTOM))
        # MeshCat's 20 m grid loses its near lines in software WebGL; ours fits the arms.
        visualizer["/Grid"].set_property("visible", False)
        # MeshCat's axes mark the page's origin, which is the fleet's middle (see above).
        visualizer["/Axes"].set_property("visible", False)
        import meshcat.geometry as mg

        visualizer["origin"].set_object(mg.triad(ORIGIN_AXES_M))

    def frame(self, bounds: Sequence[Box]) -> None:
        """Lay the grid under every arm and point the camera at them all.

        The middle of the fleet goes to the page's origin, around which the
        camera orbits; the camera sits in ``/Cameras/default/rotated``, a
        frame turned +90 deg about x (three.js is y-up).
        """
        import meshcat.geometry as mg

        box = scene_box(bounds)
        grid = grid_lines(box)
        if self._grid is None or not np.array_equal(grid, self._grid):
            self._visualizer["ground"].set_object(
                mg.LineSegments(mg.PointsGeometry(grid), mg.LineBasicMaterial(color=GRID_COLOR))
            )
            self._grid = grid
        target, position = camera_placement(box)
        shift = np.eye(4)
        shift[:3, 3] = -target
        self._visualizer.set_transform(shift)  # /meshcat
        dx, dy, dz = (position - target).tolist()
        self._visualizer["/Cameras/default/rotated/<object>"].set_property(
            "position", [dx, dz, -dy]
        )
