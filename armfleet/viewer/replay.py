"""Standalone HTML replay: the scene, MeshCat's script and an animation of the run.

The file needs no server: it holds MeshCat's ``main.min.js``, the commands
that build the scene (taken from the viewer server) and one ``set_animation``
command with a track set (position + quaternion per visual node, plus the
``tool0`` landmark) for each arm, and one for each scene object's node.
Identical mesh files, loaded once per arm in the live scene, are stored and
parsed once, as in the live page.
"""

from __future__ import annotations

import base64
import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import umsgpack

from armfleet.viewer.arm_visual import ArmVisual
from armfleet.viewer.bridge import OWN_PAGE_FOLDER, meshcat_page_folder, share_mesh
from armfleet.viewer.object_visual import ObjectVisual
from armfleet.viewer.recorder import Track

MESH_CACHE_SCRIPT = "armfleet-mesh-cache.js"


@dataclass(frozen=True)
class RecordedArm:
    """An arm of the replay: its visual (node paths, kinematics) and its recording."""

    visual: ArmVisual
    track: Track


@dataclass(frozen=True)
class RecordedObject:
    """A scene object of the replay: its visual (node, local transform) and its poses."""

    visual: ObjectVisual
    track: Track


def quaternions_xyzw(rotations: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Unit quaternions ``[x, y, z, w]`` (three.js order) of rotation matrices ``(..., 3, 3)``."""
    r = rotations
    trace = r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2]
    # 4 w^2, 4 x^2, 4 y^2, 4 z^2: build the quaternion from the largest one.
    squares = np.stack(
        [
            1.0 + trace,
            1.0 + 2.0 * r[..., 0, 0] - trace,
            1.0 + 2.0 * r[..., 1, 1] - trace,
            1.0 + 2.0 * r[..., 2, 2] - trace,
        ],
        axis=-1,
    )
    wx, wy, wz = (
        r[..., 2, 1] - r[..., 1, 2],
        r[..., 0, 2] - r[..., 2, 0],
        r[..., 1, 0] - r[..., 0, 1],
    )
    xy, xz, yz = (
        r[..., 0, 1] + r[..., 1, 0],
        r[..., 0, 2] + r[..., 2, 0],
        r[..., 1, 2] + r[..., 2, 1],
    )
    # Rows: the quaternion (x, y, z, w) times 4 * its largest component.
    candidates = np.stack(
        [
            np.stack([wx, wy, wz, squares[..., 0]], axis=-1),
            np.stack([squares[..., 1], xy, xz, wx], axis=-1),
            np.stack([xy, squares[..., 2], yz, wy], axis=-1),
            np.stack([xz, yz, squares[..., 3], wz], axis=-1),
        ],
        axis=-2,
    )
    best = np.argmax(squares, axis=-1)[..., None, None]
    chosen = np.take_along_axis(candidates, best, axis=-2)[..., 0, :]
    unit: npt.NDArray[np.float64] = chosen / np.linalg.norm(chosen, axis=-1, keepdims=True)
    return unit


def _needed_keys(values: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]:
    """Keys (rows) that linear interpolation cannot skip: ends and changes."""
    changed = np.any(values[1:] != values[:-1], axis=-1)
    keep = np.ones(len(values), dtype=bool)
    keep[1:-1] = changed[:-1] | changed[1:]
    return keep


def _track(name: str, kind: str, frames: npt.NDArray[np.int_], values: Any) -> dict[str, Any]:
    keep = _needed_keys(values)
    return {
        "name": name,
        "type": kind,
        "keys": [
            {"time": int(t), "value": v}
            for t, v in zip(frames[keep].tolist(), values[keep].tolist(), strict=True)
        ],
    }


def arm_animations(arm: RecordedArm, fps: float) -> list[dict[str, Any]]:
    """MeshCat animations (path + clip) of one arm: every visual node and ``tool0``."""
    positions = arm.track.array()
    if not len(positions):
        return []
    poses = np.array([arm.visual.poses(q) for q in positions])  # frames x nodes x 4 x 4
    translations = poses[:, :, :3, 3]
    quaternions = quaternions_xyzw(poses[:, :, :3, :3])
    frames = np.arange(arm.track.first_frame, arm.track.first_frame + len(positions))
    animations = []
    paths = (*arm.visual.geometry_paths, arm.visual.tool0_path)
    for i, path in enumerate(paths):
        tracks = [
            _track(".position", "vector3", frames, translations[:, i]),
            _track(".quaternion", "quaternion", frames, quaternions[:, i]),
        ]
        animations.append({"path": path, "clip": {"fps": fps, "name": "default", "tracks": tracks}})
    if arm.track.first_frame > 0:  # spawned during the run: hidden until then
        animations.append(_appear(arm.visual.node, arm.track.first_frame, fps))
    return animations


def _appear(node: str, first_frame: int, fps: float) -> dict[str, Any]:
    """Hidden until ``first_frame``: for what came during the run."""
    appear = {
        "name": ".visible",
        "type": "boolean",
        "keys": [{"time": 0, "value": False}, {"time": first_frame, "value": True}],
    }
    return {"path": node, "clip": {"fps": fps, "name": "default", "tracks": [appear]}}


def object_animations(recorded: RecordedObject, fps: float) -> list[dict[str, Any]]:
    """MeshCat animation of one object's node (position + quaternion)."""
    poses = recorded.track.array().reshape(-1, 4, 4)
    if not len(poses):
        return []
    frames = np.arange(recorded.track.first_frame, recorded.track.first_frame + len(poses))
    # The node's scale (a mesh's) stays as the scene set it; only its rotation is animated.
    rotations = poses[:, :3, :3] @ recorded.visual.local_rotation
    tracks = [
        _track(".position", "vector3", frames, poses[:, :3, 3]),
        _track(".quaternion", "quaternion", frames, quaternions_xyzw(rotations)),
    ]
    animations = [
        {"path": recorded.visual.node, "clip": {"fps": fps, "name": "default", "tracks": tracks}}
    ]
    if recorded.track.first_frame > 0:
        animations.append(_appear(recorded.visual.node, recorded.track.first_frame, fps))
    return animations


def animation_command(
    arms: Sequence[RecordedArm], fps: float, objects: Sequence[RecordedObject] = ()
) -> bytes:
    """One ``set_animation`` command holding every arm's and object's animations, played once."""
    animations = [animation for arm in arms for animation in arm_animations(arm, fps)]
    animations += [animation for obj in objects for animation in object_animations(obj, fps)]
    command = {
        "type": "set_animation",
        "path": "",
        "animations": animations,
        "options": {"play": True, "repetitions": 1},
    }
    packed: bytes = umsgpack.packb(command)
    return packed


def _share_meshes(commands: Sequence[bytes]) -> list[bytes]:
    """The commands, with each mesh file's text kept only in its first ``set_object``."""
    seen: set[str] = set()
    out = []
    for blob in commands:
        shared = share_mesh(blob)
        if shared is None:
            out.append(blob)
        elif shared.digest in seen:
            out.append(shared.reference)
        else:
            seen.add(shared.digest)
            out.append(shared.full)
    return out


def _script_json(value: Any) -> str:
    """JSON that is safe inside a ``<script>`` element."""
    return json.dumps(value).replace("</", "<\\/")


_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>armfleet replay</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>{meshcat}</script>
<script>{mesh_cache}</script>
<script type="application/json" id="armfleet-commands">{commands}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
armfleetCacheMeshes(viewer);
(function () {{
  const commands = JSON.parse(document.getElementById("armfleet-commands").textContent);
  for (const text of commands) {{
    const raw = atob(text);
    const bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    viewer.handle_command_bytearray(bytes);
  }}
}})();
window.armfleetReplay = {info};
</script>
</body>
</html>
"""


def replay_html(
    scene: Sequence[bytes],
    arms: Sequence[RecordedArm],
    fps: float,
    hidden: Sequence[bytes] = (),
    objects: Sequence[RecordedObject] = (),
) -> str:
    """The replay page.

    Args:
        scene: commands that build the scene, in order (from the viewer server).
        arms: the arms to animate, with their recordings.
        fps: frames per second of the recordings.
        hidden: extra commands applied after the scene (e.g. hiding live-only markers).
        objects: the scene objects to animate, with their recordings.
    """
    commands = [*_share_meshes(scene), *hidden, animation_command(arms, fps, objects)]
    meshcat = (meshcat_page_folder() / "main.min.js").read_text(encoding="utf-8")
    mesh_cache = (OWN_PAGE_FOLDER / MESH_CACHE_SCRIPT).read_text(encoding="utf-8")
    tracks = [a.track for a in arms] + [o.track for o in objects]
    frames = max((t.first_frame + len(t.positions) for t in tracks), default=0)
    info = {
        "arms": [a.visual.name for a in arms],
        "objects": [o.visual.name for o in objects],
        "frames": frames,
        "fps": fps,
    }
    return _PAGE.format(
        meshcat=meshcat,
        mesh_cache=mesh_cache,
        commands=_script_json([base64.b64encode(c).decode("ascii") for c in commands]),
        info=_script_json(info),
    )
