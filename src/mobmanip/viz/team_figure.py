"""Figures of a team (matplotlib): a top view of the robots, the object and the team's sets, and
the reach along the task axes over a sweep of the object's heading."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..measures import get_measure
from ..robot.tasks import get_task
from ..team.analysis import TeamAnalysis
from ..team.sweep import TeamSweep
from .figures import COLORS, draw_ellipse, draw_robot, extent, save_and_close

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def team_figure(
    analysis: TeamAnalysis, path: str | Path, sweep: TeamSweep | None = None, *, scale: float | None = None
) -> Path:
    """Write the team's figure (:func:`team_figure_of`; PNG by default, the suffix names the format)."""
    return save_and_close(team_figure_of(analysis, sweep, scale=scale), path, dpi=120, bbox_inches="tight")


def team_figure_of(analysis: TeamAnalysis, sweep: TeamSweep | None = None, *, scale: float | None = None) -> Figure:
    """The team's figure: a top view (robots, the object through its grasp points, the velocity
    sets of the team at the object's centre, and each robot's own kinematic set through its
    grasps dashed) and, with a sweep, the reach along each task axis against the heading, one
    panel per unit (linear axes, then angular ones). Arms are labelled with their robot's name;
    each panel's legend stands below it, outside the data.

    Args:
        analysis: the analysed team.
        sweep: a heading sweep to plot beside the top view.
        scale: metres drawn per m/s (default: the largest set fills a quarter of the view).
    """
    import matplotlib.pyplot as plt

    team = analysis.team
    space = get_task(team.task)
    kinds = [rows for rows in (space.linear_rows, space.angular_rows) if rows] if sweep is not None else []
    panels = 1 + len(kinds)
    fig, axes = plt.subplots(1, panels, figsize=(6.5 * panels, 7.0), squeeze=False, layout="constrained")
    ax = axes[0, 0]
    for member in team.members:
        draw_robot(ax, member.robot, member.q, who=member.name)
    hands = team.held_object.center + team.held_object.offsets
    ax.plot(hands[:, 0], hands[:, 1], "-", color="#8c6d31", lw=6, alpha=0.6, solid_capstyle="round", zorder=2,
            label="object (through its grasps)")  # fmt: skip
    center = team.held_object.center
    if team.object_shape is not None:  # its solid's footprint (the box around a cylinder's)
        footprint = team.object_shape.corners(center, team.object_yaw)[[0, 2, 6, 4, 0], :2]
        ax.fill(footprint[:, 0], footprint[:, 1], color="#c49a5a", alpha=0.45, zorder=1,
                label=f"object: {team.object_shape.describe()}")  # fmt: skip
    ax.plot(*center[:2], "k+", ms=10, zorder=5, label="object centre")
    velocity = [n for n in analysis.measures if get_measure(n).quantity.limits == "velocity"]
    sets = {n: analysis.measure(n) for n in velocity}
    span = float(np.ptp(np.vstack([hands[:, :2], [m.q[:2] for m in team.members]]), axis=0).max()) or 1.0
    biggest = max((_reach(s) for s in sets.values()), default=0.0)
    scale = scale if scale is not None else (0.25 * span / biggest if biggest > 0 else 1.0)
    for k, (name, task_set) in enumerate(sets.items()):
        draw = draw_ellipse if task_set.kind == "ellipsoid" else _draw_shadow
        label = f"team: {get_measure(name).label}"
        draw(ax, task_set, center, scale, color=COLORS[k % len(COLORS)], lw=2, label=label)  # type: ignore[arg-type]  # chosen by kind
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
                    label=f"{member.name} alone: {get_measure('kinematic_polytope').label}",
                )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("$x$ (m)")
    ax.set_ylabel("$y$ (m)")
    ax.set_title(f"team {team.name}, {team.task} task: sets at {scale:.3g} m per m/s", fontsize=10)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=7.5, frameon=False)
    if sweep is not None:
        for ax, rows in zip(axes[0, 1:], kinds):
            _sweep_panel(ax, sweep, rows)
    return fig


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


def _sweep_panel(ax, sweep: TeamSweep, rows) -> None:
    """Reach along the task axes ``rows`` (all linear or all angular: one unit) against the
    heading offset, for the measures of the first measure's quantity; markers by the limiting
    robot; the legend below the panel."""
    from .labels import task_unit

    first = get_measure(sweep.measures[0]).quantity
    shown = [n for n in sweep.measures if get_measure(n).quantity == first]  # one kind of units
    axes_names = get_task(sweep.task).labels
    ok = [p for p in sweep.points if p.reachable]
    x = np.array([p.offset_deg for p in ok])
    robots = sorted({r for p in ok for row in p.limiting.values() for r in row if r})
    markers = dict(zip(robots, "os^vD<>"))
    for k, name in enumerate(shown):
        for style_k, j in enumerate(rows):
            y = np.array([p.reach[name][j] for p in ok])
            style = ("-", "--", ":", "-.")[style_k % 4]
            label = f"{get_measure(name).label} along ${axes_names[j]}$"
            ax.plot(x, y, style, color=COLORS[k % len(COLORS)], label=label)
            for robot in robots:
                pick = np.array([p.limiting[name][j] == robot for p in ok], dtype=bool)
                ax.plot(x[pick], y[pick], markers[robot], color=COLORS[k % len(COLORS)], ms=4, mfc="none")
    for robot in robots:
        ax.plot([], [], markers[robot], color="black", mfc="none", label=f"limited by {robot}")
    angular = bool(get_task(sweep.task).angular[rows[0]])
    ax.set_xlabel("object heading change (\N{DEGREE SIGN})")
    ax.set_ylabel(
        f"{'angular' if angular else 'linear'} reach along the task axes ({task_unit(first, sweep.task, rows)})"
    )
    ax.set_title("heading sweep (unreachable headings left out)", fontsize=10)
    ax.grid(True, lw=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=7.5, frameon=False)
