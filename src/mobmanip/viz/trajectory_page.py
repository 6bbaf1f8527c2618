"""A trajectory in the viewer: the robot moving with its ellipsoids, and a self-contained page.

Each frame is one sample of the trajectory: the robot at q, the kinematic ellipsoid and the
dynamic ellipsoid *in motion* (:mod:`mobmanip.motion`) around the object. Frames follow each
other at the trajectory's own pace (meshcat interpolates between them), so the exported page
plays the motion in real time.
"""

from __future__ import annotations

import dataclasses
import types
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..analysis.single import Analysis, analyze
from ..errors import ArgumentError
from ..motion.in_motion import motion_terms
from ..motion.trajectory import Trajectory
from ..robot.model import Robot
from ..terms.grasp import HeldObject
from .scene import Frame

if TYPE_CHECKING:
    from ..motion.carry import CarryResult

#: Frames drawn at most: a longer trajectory is thinned to about this many.
MAX_FRAMES = 200


def motion_analysis(
    robot: Robot,
    q: np.ndarray,
    x: np.ndarray,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
) -> Analysis:
    """``analyze`` at q with its ``dynamic`` ellipsoid replaced by the one in motion at x."""
    analysis = analyze(
        robot, q, task, object_mass=object_mass, held_object=held_object, decoupled=decoupled, method="exact"
    )
    terms = motion_terms(
        robot, q, x, analysis.task, object_mass=object_mass, held_object=held_object, decoupled=decoupled
    )
    measures = dict(analysis.measures)
    measures["dynamic"] = terms.dynamic()
    return dataclasses.replace(analysis, measures=types.MappingProxyType(measures))


def joined_runs(parts: list[np.ndarray]) -> np.ndarray:
    """Samples of consecutive runs joined in one array: each run's last sample is the next one's
    first, so it is kept once."""
    return np.concatenate([part[:-1] for part in parts[:-1]] + [parts[-1]])


def self_motion_notes(preparation_t: np.ndarray | None) -> list[str]:
    """The page's note on the self-motion before the path (its time stamps, s), none without one."""
    if preparation_t is None:
        return []
    return [
        f"0 to {preparation_t[-1] - preparation_t[0]:.2f} s: the self-motion to a better posture, the object "
        "held still; then the path"
    ]


def frame_samples(n: int, every: int | None = None) -> np.ndarray:
    """The sample indices drawn: every ``every``-th (default: about :data:`MAX_FRAMES` in all),
    always the last."""
    if every is None:
        every = max(1, int(np.ceil((n - 1) / (MAX_FRAMES - 1)))) if n > 1 else 1
    if not isinstance(every, (int, np.integer)) or every < 1:
        raise ArgumentError(f"every must be a positive whole number of samples, got {every!r}")
    picked = list(range(0, n, int(every)))
    if picked[-1] != n - 1:
        picked.append(n - 1)
    return np.array(picked)


def trajectory_frames(
    robot: Robot,
    trajectory: Trajectory,
    task: str | None = None,
    *,
    every: int | None = None,
    object_mass: float | None = None,
    decoupled: bool = False,
) -> tuple[list[Frame], np.ndarray]:
    """The frames of a trajectory's animation and the time (s) of each frame from the start.

    Args:
        robot: the robot.
        trajectory: the motion.
        task, object_mass, decoupled: as :func:`mobmanip.analysis.analyze`.
        every: draw every ``every``-th sample (default: about :data:`MAX_FRAMES` frames).
    """
    picked = frame_samples(len(trajectory), every)
    frames = []
    for i in picked:
        analysis = motion_analysis(
            robot, trajectory.q[i], trajectory.x[i], task, object_mass=object_mass, decoupled=decoupled
        )
        frames.append(Frame(trajectory.q[i], analysis, None, 0.0, f"t = {trajectory.t[i]:.3f} s"))
    return frames, trajectory.t[picked] - trajectory.t[0]


def animate_trajectory(viewer, frames: list[Frame], times: np.ndarray, *, play: bool = True, notes=()):
    """Send the frames to an :class:`~mobmanip.viz.scene.EllipsoidViewer` as one animation at
    the trajectory's pace (frames equally spaced in time; the last at the trajectory's end);
    ``notes`` go under the legend."""
    step = float(times[-1] / (len(times) - 1)) if len(times) > 1 else 0.1
    return viewer.animate(frames, step=step, play=play, notes=notes)


def export_trajectory_page(
    robot: Robot,
    trajectory: Trajectory,
    path: str | Path,
    task: str | None = None,
    *,
    every: int | None = None,
    object_mass: float | None = None,
    decoupled: bool = False,
    notes: Sequence[str] = (),
) -> Path:
    """Write a self-contained HTML page that plays the trajectory with its ellipsoids moving along
    (:func:`trajectory_frames`'s frames at its pace), ``notes`` under the legend.

    Returns:
        The page's path.
    """
    from .scene import EllipsoidViewer

    frames, times = trajectory_frames(
        robot, trajectory, task, every=every, object_mass=object_mass, decoupled=decoupled
    )
    with EllipsoidViewer(robot) as viewer:
        animate_trajectory(viewer, frames, times, notes=notes)
        return viewer.export_html(path)


def export_carry_page(
    robot: Robot,
    result: CarryResult,
    path: str | Path,
    *,
    every: int | None = None,
    object_mass: float | None = None,
) -> Path:
    """Write the page of ``mobmanip carry ... --export PAGE.html``: the QP motion (the self-motion
    before the path first, when there is one) played with its in-motion ellipsoids, as
    :func:`export_trajectory_page` plays a trajectory; the camera follows the robot when it drives
    off (:func:`mobmanip.viz.page.animation_request`).

    Returns:
        The page's path.
    """
    from ..motion.trajectory import trajectory_from_samples

    runs = [run for run in (result.preparation, result.motion) if run is not None]
    t, q = joined_runs([run.t for run in runs]), joined_runs([run.q for run in runs])
    notes = self_motion_notes(None if result.preparation is None else result.preparation.t)
    return export_trajectory_page(robot, trajectory_from_samples(robot, t, q), path, result.task, every=every,
                                  object_mass=object_mass, notes=notes)  # fmt: skip
