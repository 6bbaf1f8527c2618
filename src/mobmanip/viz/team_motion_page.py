"""A team's motion in the viewer: every robot moving, the object carried, the team's set along.

The page of ``mobmanip team-carry ... --export PAGE.html``: the QP motion of
:func:`mobmanip.coordination.carry.team_carry` (the self-motion before the path first, when there
is one), drawn by :meth:`mobmanip.viz.team_scene.TeamViewer.animate`. Each frame is one sample
of the motion: every robot at its own configuration, the object where its hands carry it
(:meth:`~mobmanip.coordination.carry.TeamCarryResult.carried`) and the team's kinematic
ellipsoid there (:data:`MEASURES`; the team's set at rest of the robots at that configuration,
drawn as the single robot's: only its linear part). Frames follow each other at the motion's
own pace, thinned as the single robot's (:func:`mobmanip.viz.trajectory_page.frame_samples`),
and the scales and the camera are fitted over all of them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..coordination.carry import TeamCarryResult
from ..team.analysis import analyze_team
from .team_scene import TeamFrame, TeamViewer, team_scales
from .trajectory_page import frame_samples, joined_runs, self_motion_notes

__all__ = ["MEASURES", "export_team_motion_page", "team_motion_frames"]

#: The team's sets drawn along its motion.
MEASURES = ("kinematic",)


def team_motion_frames(result: TeamCarryResult, *, every: int | None = None) -> tuple[list[TeamFrame], np.ndarray]:
    """The frames of a team carry's QP motion and the time (s) of each from the start.

    Args:
        result: the team carry.
        every: draw every ``every``-th sample (default: about
            :data:`~mobmanip.viz.trajectory_page.MAX_FRAMES` frames).
    """
    runs = [run for run in (result.preparation, result.motion) if run is not None]
    t = joined_runs([run.t for run in runs])
    qs = [joined_runs([run.q[i] for run in runs]) for i in range(len(result.team.members))]
    picked = frame_samples(len(t), every)
    frames = []
    for k in picked:
        team, turn = result.carried([q[k] for q in qs])
        phase = "self-motion" if k < len(t) - len(result.motion.t) else "path"
        frames.append(TeamFrame(analyze_team(team, MEASURES), turn, f"t = {t[k]:.3f} s ({phase})"))
    return frames, t[picked] - t[0]


def export_team_motion_page(
    result: TeamCarryResult, path: str | Path, *, every: int | None = None
) -> tuple[Path, list[str]]:
    """Write a self-contained HTML page that plays the team's QP motion.

    Returns:
        The page's path and one note per mesh left out of the drawing.
    """
    frames, times = team_motion_frames(result, every=every)
    notes = self_motion_notes(None if result.preparation is None else result.preparation.t)
    with TeamViewer(frames[0].analysis, scales=team_scales(f.analysis for f in frames)) as viewer:
        viewer.animate(frames, times, notes=notes)
        return viewer.export_html(path), list(viewer.mesh_notes)
