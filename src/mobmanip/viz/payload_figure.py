"""The payload map's figure (``mobmanip payload --map --out``): the heaviest object over the object
positions around the robot, a polar heat map as a sweep's (:mod:`mobmanip.viz.sweep_plot`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .sweep_plot import _polar_panel

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..sweep.payload_map import PayloadMap


def payload_map_figure(result: PayloadMap) -> Figure:
    """The heaviest object (kg) at each object position: angle from the platform's heading (up,
    counter-clockwise), radius the distance from the arms' reference point; positions without a
    payload (out of reach, or the robot cannot do it with no object) left blank, and the heaviest
    marked."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..measures import ACCELERATION
    from .labels import task_unit

    fig = Figure(figsize=(7.6, 5.4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="polar")
    mass = np.where(result.status == "bounded", result.mass, np.nan)
    finite = mass[np.isfinite(mass)]
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    mesh = _polar_panel(ax, result.angle_deg, result.distance, mass, vmin, vmax)
    best = result.best()
    if best is not None:
        ax.plot(np.radians(result.angle_deg[best[0]]), result.distance[best[1]], marker="*", color="white",
                markeredgecolor="black", markersize=13, linestyle="none")  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="heaviest object (kg)", shrink=0.8, pad=0.12)
    values = ", ".join(f"{v:g}" for v in result.acceleration)
    unit = task_unit(ACCELERATION, result.task)
    asked = f"given the acceleration ({values}) {unit}" if np.any(result.acceleration) else "held still"
    where = "on the floor" if result.constraints else "ideal model"
    fig.suptitle(f"{result.robot}, {result.task} task, {where}: heaviest object {asked}", fontsize=10)
    return fig
