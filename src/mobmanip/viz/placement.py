"""The figure of a base placement: the best start and the optimum from above, each with the
objective's ellipsoid (its horizontal shadow) drawn at the object, on one scale."""

from __future__ import annotations

import math
from pathlib import Path
from typing import cast

import numpy as np

from ..analysis.single import analyze
from ..robot.model import Robot
from ..sets.ellipsoid import Ellipsoid


def placement_figure(
    robot: Robot,
    placement,
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
