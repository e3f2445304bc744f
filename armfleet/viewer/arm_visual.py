"""One arm in the viewer: its meshes, its landmark frames and its motion target.

Meshes come from Pinocchio's visual model of the arm's own URDF (absolute mesh
paths, prefixed names) and load once, under ``/meshcat/armfleet/<name>``.
Live updates then only move nodes: every visual geometry, the ``tool0``
landmark and the target marker.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from armfleet import topics
from armfleet.messages import JointCommand
from armfleet.viewer.commands import TransformPacker, Updates, property_command

if TYPE_CHECKING:
    from armfleet.arms.arm import Arm
    from armfleet.runtime.bus import Subscription

#: Joint motion below which an arm is not redrawn [rad or m].
REDRAW_TOLERANCE = 1e-5
LANDMARK_AXIS_M = 0.15
TARGET_RADIUS_M = 0.025
TARGET_COLOR = 0xFF7F00

Poses = npt.NDArray[np.float64]


class ArmVisual:
    """Loads one arm into a shared ``meshcat.Visualizer`` and makes its live updates.

    What it reads from ``arm`` (a recording's replay passes look-alikes):
    ``name``, ``namespace``, ``description`` (``urdf``, ``prefix``, ``base_link``,
    ``tool0``), ``kinematics`` (``model``, ``arm_indices``), ``body.position``,
    ``is_moving`` and ``position_controller.arm.bus``, whose
    ``/<name>/position_controller/commands`` give the motion targets.

    Args:
        arm: a ready arm.
        visualizer: the viewer's ``meshcat.Visualizer`` (root ``/meshcat``).
        show_frames: show the ``base_link`` and ``tool0`` frames.
        show_target: show a marker at ``tool0`` of the current motion target.
        mesh_loader: a ``coal.CachedMeshLoader`` shared by the viewer's arms, so
            that each mesh file is read once (a Panda's take ~0.6 s), or None.
    """

    def __init__(
        self,
        arm: Arm,
        visualizer: Any,
        show_frames: bool,
        show_target: bool,
        mesh_loader: Any = None,
    ) -> None:
        import meshcat.geometry as mg
        import pinocchio as pin
        from pinocchio.visualize import MeshcatVisualizer

        self._pin = pin
        self.arm = arm
        self.name = arm.name
        #: MeshCat path of the arm's node.
        self.node = f"/meshcat/armfleet/{arm.name}"
        model = arm.kinematics.model
        self.model = model
        self.geometry = pin.buildGeomFromUrdfString(
            model, arm.description.urdf, pin.GeometryType.VISUAL, mesh_loader=mesh_loader
        )
        self._data = model.createData()
        self._geometry_data = pin.GeometryData(self.geometry)
        self._target_data = model.createData()
        self._tool0 = model.getFrameId(arm.description.tool0)
        base_link = model.getFrameId(arm.description.base_link)

        loader = MeshcatVisualizer(model, None, self.geometry)
        loader.initViewer(viewer=visualizer)
        # Loading also places the meshes: at the arm's pose, not the model's zero.
        pin.forwardKinematics(model, loader.data, arm.body.position)
        loader.loadViewerModel(rootNodeName=f"armfleet/{arm.name}")
        #: MeshCat paths of the visual geometries, in visual-model order.
        self.geometry_paths = tuple(
            visualizer[loader.getViewerNodeName(g, pin.GeometryType.VISUAL)].path.lower()
            for g in self.geometry.geometryObjects
        )
        self.tool0_path = f"{self.node}/landmarks/tool0"
        self._packer = TransformPacker((*self.geometry_paths, self.tool0_path))
        scale = [np.append(g.meshScale, 1.0) for g in self.geometry.geometryObjects]
        scales = np.array([*scale, np.ones(4)])[:, None, :]
        #: Column scaling of each pose (MeshCat scales meshes through their matrix).
        self._scale: Poses | None = None if np.all(scales == 1.0) else scales

        root = visualizer[f"armfleet/{arm.name}"]
        landmarks = root["landmarks"]
        pin.framesForwardKinematics(model, self._data, arm.body.position)
        for short, frame in (("base_link", base_link), ("tool0", self._tool0)):
            landmarks[short].set_object(mg.triad(LANDMARK_AXIS_M))
            landmarks[short].set_transform(self._data.oMf[frame].homogeneous)
        landmarks.set_property("visible", show_frames)
        targets = root["targets"]
        targets["tool0"].set_object(
            mg.Sphere(TARGET_RADIUS_M),
            mg.MeshLambertMaterial(color=TARGET_COLOR, transparent=True, opacity=0.7),
        )
        targets["tool0"].set_property("visible", False)
        targets.set_property("visible", show_target)
        self.target_path = f"{self.node}/targets/tool0"
        self._target_packer = TransformPacker((self.target_path,))
        self._target_shown = False
        self._target_pose: Poses | None = None
        self._last_q: npt.NDArray[np.float64] | None = None
        bus = arm.position_controller.arm.bus
        self._subscription: Subscription | None = bus.subscribe(
            topics.position_commands(arm.name), self._on_command
        )

    # -- live updates -------------------------------------------------------------------
    def poses(self, q: npt.NDArray[np.float64]) -> Poses:
        """World poses (n x 4 x 4) of the visual geometries, then ``tool0``, at ``q``."""
        pin = self._pin
        pin.updateGeometryPlacements(self.model, self._data, self.geometry, self._geometry_data, q)
        pin.updateFramePlacement(self.model, self._data, self._tool0)
        homogeneous = [placement.homogeneous for placement in self._geometry_data.oMg]
        homogeneous.append(self._data.oMf[self._tool0].homogeneous)
        poses: Poses = np.array(homogeneous)
        if self._scale is not None:
            poses *= self._scale
        return poses

    def collect(self, into: Updates) -> None:
        """Add what changed since the last call to ``into``: poses, target marker."""
        q = self.arm.body.position
        last = self._last_q
        if last is None or float(np.max(np.abs(q - last))) > REDRAW_TOLERANCE:
            self._packer.pack(self.poses(q), into)
            self._last_q = q.copy()
        target = self._target_pose
        if target is not None:
            self._target_pose = None
            self._target_packer.pack(target[None], into)
        moving = self.arm.is_moving
        if moving != self._target_shown:
            self._target_shown = moving
            key, data = property_command(self.target_path, "visible", moving)
            into[key] = data

    def _on_command(self, command: JointCommand) -> None:
        q = self.arm.body.position.copy()
        q[self.arm.kinematics.arm_indices] = command.positions
        self._pin.framesForwardKinematics(self.model, self._target_data, q)
        self._target_pose = np.array(self._target_data.oMf[self._tool0].homogeneous)

    # -- scene --------------------------------------------------------------------------
    def bounds(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(min, max) corners [m] of the arm's frame origins at its current pose."""
        return arm_bounds(self.arm, self._data)

    def close(self) -> None:
        """Stop following the arm's commands."""
        if self._subscription is not None:
            self._subscription.cancel()
            self._subscription = None


def arm_bounds(
    arm: Arm, data: Any = None
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(min, max) corners [m] of ``arm``'s frame origins at its current pose.

    Needs only the arm's kinematics, not its meshes: the viewer frames an arm with it
    before the meshes are sent.

    Args:
        arm: a ready arm (or a replay's look-alike).
        data: Pinocchio data of the arm's model to compute in; a new one if None.
    """
    import pinocchio as pin

    model = arm.kinematics.model
    data = model.createData() if data is None else data
    pin.framesForwardKinematics(model, data, arm.body.position)
    prefix = arm.description.prefix
    origins = np.array(
        [
            placement.translation
            for frame, placement in zip(model.frames, data.oMf, strict=True)
            if frame.name.startswith(prefix)
        ]
    )
    return origins.min(axis=0), origins.max(axis=0)
