"""Figures of a team (matplotlib): a top view of the robots, the object and the team's sets, and
the reach along the task axes over a sweep of the object's heading."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..measures import get_measure
from ..robot.tasks import get_task
from ..support.files import save_figure
from ..team.analysis import TeamAnalysis
from ..team.sweep import TeamSweep
from .figures import COLORS, draw_ellipse, draw_robot, extent


def team_figure(
    analysis: TeamAnalysis, path: str | Path, sweep: TeamSweep | None = None, *, scale: float | None = None
) -> Path:
    """Write the team's figure: a top view (robots, the object through its grasp points, the
    velocity sets of the team at the object's centre, and each robot's own kinematic set through
    its grasps dashed) and, with a sweep, the reach along each task axis against the heading.

    Args:
        analysis: the analysed team.
        path: the file (its suffix names the format; PNG by default).
        sweep: a heading sweep to plot beside the top view.
        scale: metres drawn per m/s (default: the largest set fills a quarter of the view).
    """
    import matplotlib.pyplot as plt

    team = analysis.team
    panels = 2 if sweep is not None else 1
    fig, axes = plt.subplots(1, panels, figsize=(6.5 * panels, 6.0), squeeze=False)
    ax = axes[0, 0]
    for member in team.members:
        draw_robot(ax, member.robot, member.q)
    hands = team.held_object.center + team.held_object.offsets
    ax.plot(hands[:, 0], hands[:, 1], "-", color="#8c6d31", lw=6, alpha=0.6, solid_capstyle="round", zorder=2)
    center = team.held_object.center
    ax.plot(*center[:2], "k+", ms=10, zorder=5)
    velocity = [n for n in analysis.measures if get_measure(n).quantity.limits == "velocity"]
    sets = {n: analysis.measure(n) for n in velocity}
    span = float(np.ptp(np.vstack([hands[:, :2], [m.q[:2] for m in team.members]]), axis=0).max()) or 1.0
    biggest = max((_reach(s) for s in sets.values()), default=0.0)
    scale = scale if scale is not None else (0.25 * span / biggest if biggest > 0 else 1.0)
    for k, (name, task_set) in enumerate(sets.items()):
        draw = draw_ellipse if task_set.kind == "ellipsoid" else _draw_shadow
        draw(ax, task_set, center, scale, color=COLORS[k % len(COLORS)], lw=2, label=f"team {name}")  # type: ignore[arg-type]  # chosen by kind
    if "kinematic_polytope" in sets:
        for i, member in enumerate(team.members):
            own = analysis.member_set("kinematic_polytope", i)
            if not own.empty and _reach(own) < 4 * _reach(sets["kinematic_polytope"]):
                _draw_shadow(
                    ax,
                    own,
                    center,
                    scale,
                    color=COLORS[(i + 2) % len(COLORS)],
                    lw=1,
                    ls="--",
                    label=f"{member.name} alone",
                )
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"team {team.name}: {team.task}, {scale:.3g} m per m/s")
    ax.legend(loc="best", fontsize=8)
    if sweep is not None:
        _sweep_panel(axes[0, 1], sweep)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)
    return Path(path)


def _shadow(polytope) -> np.ndarray:
    """The outline (k, 2) of a polytope's shadow on the horizontal task coordinates: the convex
    hull (scipy) of its vertices' first two coordinates, counter-clockwise."""
    from scipy.spatial import ConvexHull

    points = polytope.vertices[:, :2]
    if polytope.dim == 2:
        return points
    return points[ConvexHull(points).vertices]


def _reach(task_set) -> float:
    """How far a set is drawn from the object's centre (task units)."""
    if task_set.empty:
        return 0.0
    if task_set.kind == "ellipsoid":
        return extent(task_set)
    return float(np.max(np.linalg.norm(_shadow(task_set), axis=1), initial=0.0))


def _draw_shadow(ax, polytope, at, scale, **style) -> None:
    if polytope.empty:
        return
    points = np.asarray(at[:2]) + scale * _shadow(polytope)
    closed = np.vstack([points, points[:1]])
    ax.plot(closed[:, 0], closed[:, 1], zorder=4, **style)


def _sweep_panel(ax, sweep: TeamSweep) -> None:
    """Reach along each task axis against the heading offset, for the measures of the first
    measure's quantity (one kind of units); markers by the limiting robot."""
    first = get_measure(sweep.measures[0]).quantity
    shown = [n for n in sweep.measures if get_measure(n).quantity == first]  # one kind of units
    labels = first.units
    axes_names = get_task(sweep.task).labels
    ok = [p for p in sweep.points if p.reachable]
    x = np.array([p.offset_deg for p in ok])
    robots = sorted({r for p in ok for row in p.limiting.values() for r in row if r})
    markers = dict(zip(robots, "os^vD<>"))
    for k, name in enumerate(shown):
        for j, axis in enumerate(axes_names):
            y = np.array([p.reach[name][j] for p in ok])
            style = ("-", "--", ":", "-.")[j % 4]
            ax.plot(x, y, style, color=COLORS[k % len(COLORS)], label=f"{name} {axis}")
            for robot in robots:
                pick = np.array([p.limiting[name][j] == robot for p in ok], dtype=bool)
                ax.plot(x[pick], y[pick], markers[robot], color=COLORS[k % len(COLORS)], ms=4, mfc="none")
    for robot in robots:
        ax.plot([], [], markers[robot], color="black", mfc="none", label=f"limited by {robot}")
    ax.set_xlabel("object heading change (deg)")
    ax.set_ylabel(f"reach along the task axis ({labels})")
    ax.set_title("heading sweep (unreachable headings left out)")
    ax.legend(fontsize=7)
