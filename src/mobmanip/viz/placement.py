"""Figures of base placement: a placement's best start and optimum from above, each with the
objective's ellipsoid (its horizontal shadow) drawn at the object, on one scale
(:func:`placement_figure`); and a placement map as a heat map over platform positions
(:func:`plot_placement_map`)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from ..analysis.single import analyze
from ..robot.model import Robot
from ..sets.ellipsoid import Ellipsoid

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..placement.maps import PlacementMap
    from ..placement.optimize import Placement


def placement_figure(
    robot: Robot,
    placement: Placement,
    path: str | Path,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
) -> Path:
    """Write the figure of a :class:`mobmanip.placement.Placement` (PNG or SVG by the suffix).

    One panel per configuration -- the best start (the reference hold placed at the object) when
    there is one, then the optimum -- with the robot drawn from above
    (:func:`mobmanip.viz.figures.draw_robot`), the object (+) and the objective's ellipsoid at
    the object; the ellipses share one scale (the largest semi-axis drawn 0.6 m long).
    """
    from ..support.files import save_figure
    from .figures import draw_ellipse, draw_robot, plt

    objective = placement.objective
    unit = "m/s" if objective.ellipsoid == "kinematic" else "m/s^2"
    panels = []
    for caption, q, value in (
        ("best start", placement.start_q, placement.start_value),
        ("optimum", placement.q, placement.value),
    ):
        if q is not None:
            analysis = analyze(robot, q, task, object_mass=object_mass, decoupled=decoupled)
            ellipsoid = cast(Ellipsoid, analysis.measures[objective.ellipsoid])  # objectives are of ellipsoids
            panels.append((f"{caption}: {value:.4g}", q, ellipsoid, analysis))
    largest = max((float(p[2].semi_axes[0]) for p in panels if not p[2].empty), default=1.0)
    scale = 0.6 / largest if largest > 0 else 1.0
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 5.6), squeeze=False)
    for ax, (caption, q, ellipsoid, analysis) in zip(axes[0], panels):
        draw_robot(ax, robot, q)
        point = analysis.held_object.center
        points = [np.asarray(q[:2])[None], np.asarray(point[:2])[None]]
        if not ellipsoid.empty:
            points.append(draw_ellipse(ax, ellipsoid, point, scale, color="#1b9e77", lw=1.8, label=objective.ellipsoid))
        ax.plot(*point[:2], "k+", ms=12, zorder=5)
        everything = np.vstack(points)
        middle = 0.5 * (everything.min(axis=0) + everything.max(axis=0))
        side = float(np.max(everything.max(axis=0) - everything.min(axis=0))) + 2.0  # the robot's size around
        ax.set_xlim(middle[0] - side / 2, middle[0] + side / 2)
        ax.set_ylim(middle[1] - side / 2, middle[1] + side / 2)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, lw=0.3)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{caption}")
        if not ellipsoid.empty:
            ax.legend(loc="upper right", fontsize=8)
    x, y, heading = placement.platform
    target = ", ".join(f"{v:g}" for v in placement.target)
    fig.suptitle(
        f"{robot.name}: {objective.name}, object at ({target}) m  (ellipse scale: 1 {unit} = {scale:.3g} m)\n"
        f"optimum: platform x {x:.3f} m, y {y:.3f} m, heading {math.degrees(heading):.1f} deg"
    )
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
    return Path(path)


def placement_map_figure(placement_map: PlacementMap, title: str | None = None) -> Figure:
    """A heat map of a :class:`mobmanip.placement.maps.PlacementMap`'s best value over headings,
    arrows for the best heading, the object (star) and the best cell (circle)."""
    from .figures import plt

    grid = placement_map
    values, heading = grid.best_over_headings()
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    masked = np.ma.masked_invalid(values)
    mesh = ax.pcolormesh(grid.x, grid.y, masked, shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=grid.objective.name)
    ok = ~np.isnan(values)
    X, Y = np.meshgrid(grid.x, grid.y)
    step = max(1, max(len(grid.x), len(grid.y)) // 15)
    sel = np.zeros_like(ok)
    sel[::step, ::step] = True
    sel &= ok
    ax.quiver(X[sel], Y[sel], np.cos(heading[sel]), np.sin(heading[sel]), color="white", scale=25, width=0.004)
    ax.plot(*grid.target[:2], marker="*", color="red", markersize=14, linestyle="none", label="object")
    if ok.any():
        _, q, _ = grid.best()
        ax.plot(q[0], q[1], marker="o", markerfacecolor="none", markeredgecolor="red", markersize=12,
                linestyle="none", label="best platform position")  # fmt: skip
    ax.set_xlabel("platform x (m)")
    ax.set_ylabel("platform y (m)")
    ax.set_aspect("equal")
    ax.set_title(title or f"best {grid.objective.name} over heading and posture")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def plot_placement_map(placement_map: PlacementMap, path: str | Path, title: str | None = None) -> Path:
    """Write :func:`placement_map_figure` (PNG or SVG by the file's suffix) atomically; returns the path."""
    from ..support.files import save_figure
    from .figures import plt

    fig = placement_map_figure(placement_map, title)
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
    return Path(path)
