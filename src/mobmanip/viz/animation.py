"""What an animated viewer page is made of, for one robot or a team: keyframes of the robots'
visual geometry and of the drawn sets, and what the camera frames.

Both :meth:`mobmanip.viz.scene.EllipsoidViewer.animate` (one robot) and
:meth:`mobmanip.viz.team_scene.TeamViewer.animate` (a team) build their meshcat animation from
these pieces: a keyframe is a list of :data:`Pose` (a scene path, its 4x4 transform and, for a
set, its scale) written at one time; the camera frames the robots, the object and the sets at up
to :data:`CAMERA_FRAMES` frames of the animation (:func:`camera_samples`), or follows the robots
through up to :data:`FOLLOW_FRAMES` of them when they travel far
(:func:`mobmanip.viz.page.animation_request`).
"""

from __future__ import annotations

from collections.abc import Hashable, MutableMapping, Sequence

import numpy as np
import pinocchio as pin

from ..sets.taskset import TaskSet
from . import page as _page
from .shapes import DRAWINGS, ellipsoid_matrix

#: Frames an animation's camera frames at most (evenly spread, the last included).
CAMERA_FRAMES = 25
#: Frames a following camera keeps its target on at most (evenly spread, the last included).
FOLLOW_FRAMES = 100
#: The scale, along each axis, of a set hidden in a keyframe (a set without points, or absent,
#: then): it shrinks to nothing.
HIDDEN_SCALE = 1e-6

#: One object's keyframe: its scene path, its 4x4 pose and its scale (3,), or ``None`` to leave
#: the scale alone.
Pose = tuple[str, np.ndarray, np.ndarray | None]


def camera_samples(n: int, limit: int = CAMERA_FRAMES) -> np.ndarray:
    """Indices of the frames (of ``n``) the camera frames: all, or ``limit`` evenly spread with
    the first and the last."""
    if n <= limit:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, limit).round().astype(int))


def geometry_paths(visualizer, geometry: pin.GeometryModel) -> list[str]:
    """The scene path of each visual geometry a Pinocchio ``MeshcatVisualizer`` loaded."""
    return [visualizer.getViewerNodeName(geom, pin.GeometryType.VISUAL) for geom in geometry.geometryObjects]


def robot_poses(model: pin.Model, geometry: pin.GeometryModel, paths: Sequence[str], q: np.ndarray) -> list[Pose]:
    """The pose of each visual geometry (at its scene path in ``paths``) of a robot at ``q``."""
    data, geometry_data = model.createData(), geometry.createData()
    pin.forwardKinematics(model, data, q)
    pin.updateGeometryPlacements(model, data, geometry, geometry_data)
    return [(path, geometry_data.oMg[g].homogeneous, None) for g, path in enumerate(paths)]


def set_pose(
    path: str,
    task_set: TaskSet | None,
    task: str,
    center: np.ndarray,
    scale: float,
    thickness: float,
    previous: MutableMapping[Hashable, tuple[np.ndarray, np.ndarray]],
    key: Hashable,
) -> Pose | None:
    """A drawn set's keyframe: placed by its drawing (its rotation following the ``previous``
    keyframe of ``key``, which it updates), or shrunk to nothing where it stood when the set is
    empty or absent; ``None`` for a drawing that does not animate (it stays as first shown)."""
    if task_set is None or task_set.empty:
        return path, previous.get(key, (np.eye(4), None))[0], np.full(3, HIDDEN_SCALE)
    last = previous.get(key)
    placed = DRAWINGS[task_set.kind].keyframe(
        task_set, task, center, scale, thickness, None if last is None else last[0][:3, :3]
    )
    if placed is None:
        return None
    previous[key] = placed
    return path, placed[0], placed[1]


def write_keyframe(animation, vis, time_s: float, fps: int, poses: Sequence[Pose]) -> None:
    """Write the poses (and scales) as the keyframe at ``time_s`` (s) of a meshcat animation."""
    with animation.at_frame(vis, time_s * fps) as at:
        for path, pose, scale in poses:
            at[path].set_transform(pose)  # position and rotation tracks
            if scale is not None:
                at[path].set_property("scale", "vector3", [float(s) for s in scale])


def set_extent(
    task_set: TaskSet, task: str, center: np.ndarray, scale: float, thickness: float
) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """What the camera frames of a drawn set: points (n, 3) on a drawn ellipsoid, or the box
    around the sphere that holds another kind's drawing."""
    if task_set.kind == "ellipsoid":
        T = ellipsoid_matrix(task_set, task, center, scale, thickness)  # type: ignore[arg-type]
        return _page.DIRECTIONS @ T[:3, :3].T + T[:3, 3], []
    return np.zeros((0, 3)), [_page.sphere_box(center, DRAWINGS[task_set.kind].extent(task_set, task) * scale)]
