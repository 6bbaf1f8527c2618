"""The site figure: every object position from above, coloured by its best placement's value,
with a line to the platform position chosen for it and a tick along that platform's heading."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..placement.site import SiteResult


def site_figure(result: SiteResult, title: str | None = None) -> Figure:
    """The figure (see the module's docstring); positions without a placement are grey crosses.
    The colour bar names the objective with its unit; the legend stands below the map."""
    from ..gradients.evaluator import Objective
    from ..gradients.readings import ReadingObjective, is_reading_objective
    from .figures import plt
    from .labels import objective_label, objective_words

    task = result.task or result.site.task or "translational"
    text = result.site.objective
    objective = ReadingObjective.parse(text, task) if is_reading_objective(text) else Objective.parse(text, task)

    columns = result.columns
    table = result.table
    x, y = table[:, columns.index("x")], table[:, columns.index("y")]
    value = table[:, columns.index("value")]
    px, py = table[:, columns.index("platform_x")], table[:, columns.index("platform_y")]
    heading = np.radians(table[:, columns.index("heading_deg")])
    ok = np.isfinite(value)
    fig, ax = plt.subplots(figsize=(7.0, 6.4), layout="constrained")
    for k in np.flatnonzero(ok):
        ax.plot([x[k], px[k]], [y[k], py[k]], color="0.7", lw=0.6, zorder=1)
    tick = 0.15
    ax.quiver(px[ok], py[ok], tick * np.cos(heading[ok]), tick * np.sin(heading[ok]), angles="xy", scale_units="xy",
              scale=1.0, width=0.003, color="0.3", zorder=2)  # fmt: skip
    points = ax.scatter(x[ok], y[ok], c=value[ok], cmap="viridis", s=36, zorder=3, edgecolors="k", linewidths=0.3,
                        norm=_colour_range(value[ok]))  # fmt: skip
    if (~ok).any():
        ax.scatter(x[~ok], y[~ok], marker="x", color="0.5", s=30, zorder=3, label="no placement")
        fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", fontsize=8, frameon=False)
    if ok.any():
        fig.colorbar(points, ax=ax, label=objective_label(objective, task))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("$x$ (m)")
    ax.set_ylabel("$y$ (m)")
    reached = int(ok.sum())
    ax.set_title(title or f"{Path(result.site.robot).stem}: {reached} of {len(ok)} positions placed "
                          f"({objective_words(objective, task)})", fontsize=10)  # fmt: skip
    return fig


def _colour_range(values: np.ndarray):
    """The colour scale: the values' own range, or, where they tie up to rounding (1e-6 relative:
    a symmetric robot's positions), 1 % either side of them, so that the tie is one colour and
    the colour bar reads as the value rather than as rounding noise."""
    from matplotlib.colors import Normalize

    if values.size == 0:
        return None
    lo, hi = float(values.min()), float(values.max())
    if hi - lo > 1e-6 * max(abs(lo), abs(hi)):
        return Normalize(lo, hi)
    centre = 0.5 * (lo + hi)
    half = 0.01 * abs(centre) if centre != 0.0 else 1.0
    return Normalize(centre - half, centre + half)


def plot_site(result: SiteResult, path: str | Path, title: str | None = None) -> Path:
    """Write :func:`site_figure` (PNG or SVG by the file's suffix) atomically; returns the path."""
    from .figures import save_and_close

    return save_and_close(site_figure(result, title), path, dpi=110, bbox_inches="tight")
