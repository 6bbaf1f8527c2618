"""Plots of a sweep's index over its grid (``mobmanip sweep --plot``), ready for a paper.

Two varying axes: a heat map, polar when they are object angle and distance (0° up, 90° to the
left, like the robot seen from above facing up), drawn over the swept wedge only (an annular
sector at its true proportions), with the radial tick labels beside the wedge. A third varying
axis gives one panel per value (up to ``max_panels``, evenly picked); further axes are taken at
their first value. One varying axis: a line plot. The colour bar (or the y axis) names the index
with its unit (:func:`index_label`). Written as PNG and as vector PDF beside it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..support.files import save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..sweep.results import SweepResult

AXIS_LABELS = {
    "angle_deg": "object direction (\N{DEGREE SIGN})",
    "distance": "object distance (m)",
    "heading_deg": "platform heading (\N{DEGREE SIGN})",
    "wheel_velocity_scale": "wheel velocity scale",
    "wheel_effort_scale": "wheel effort scale",
}
FORMATS = ("png", "pdf")


def _power(unit: str, n: int) -> str:
    if n == 0:
        return ""
    base = unit if "/" not in unit else f"({unit})"
    return base if n == 1 else f"{base}$^{{{n}}}$"


def _mathtext(unit: str) -> str:
    return unit.replace("^2", "$^2$")


def index_unit(index: str, task: str) -> str:
    """The unit of a sweep index, mathtext: ``(m/s)$^{2}$`` for a planar kinematic volume,
    ``1`` for an isotropy, ``m/s`` for a planar semi-axis; ``mixed`` where the task mixes linear
    and angular axes and the index does not say which (a spatial semi-axis)."""
    from ..measures import get_measure
    from ..robot.tasks import get_task
    from ..sweep.results import check_index_name

    space = get_task(task)
    kind, what, k = check_index_name(index, space.dim, [index.partition(".")[0]])
    quantity = get_measure(kind).quantity
    linear, _, angular = quantity.units.partition(", ")
    linear, angular = _mathtext(linear), _mathtext(angular or linear)
    n_angular = len(space.angular_rows)
    n_linear = space.dim - n_angular
    if what == "isotropy":
        return "1"
    if what == "volume":
        return " ".join(u for u in (_power(linear, n_linear), _power(angular, n_angular)) if u)
    if k is not None and what == "widths":  # along task axis k
        return angular if space.angular[k - 1] else linear
    if n_angular == 0:
        return linear
    if n_linear == 0:
        return angular
    return "mixed: " + linear + ", " + angular


#: Index names whose words are not their name with spaces.
_WORDS = {"straight_line_reach": "straight-line reach"}


def index_words(index: str, task: str) -> str:
    """A sweep index in words: ``kinematic ellipsoid volume``, ``dynamic ellipsoid semi-axis 2``,
    ``kinematic polytope width along x``."""
    from ..measures import get_measure
    from ..robot.tasks import get_task
    from ..sweep.results import check_index_name

    space = get_task(task)
    kind, what, k = check_index_name(index, space.dim, [index.partition(".")[0]])
    measure = get_measure(kind)
    if k is None:
        return f"{measure.label} {_WORDS.get(what, what.replace('_', ' '))}"
    stem = dict(measure.axis_indices).get(what, what)
    if what == "widths":
        return f"{measure.label} {stem.replace('_', '-')} along {space.labels[k - 1]}"
    return f"{measure.label} {stem.replace('_', '-')} {k}"


def index_label(index: str, task: str) -> str:
    """``kinematic ellipsoid volume ((m/s)$^{2}$)``: the index in words, with its unit."""
    return f"{index_words(index, task)} ({index_unit(index, task)})"


def plot_sweep(
    result: SweepResult, index: str, path: str | Path, max_panels: int = 6, formats: Sequence[str] = FORMATS
) -> Path:
    """Plot one index over the sweep's varying grid axes (see the module's docstring) and save it.

    Args:
        result: a :class:`mobmanip.sweep.results.SweepResult`.
        index: the index name (``kinematic.volume``, ...).
        path: the PNG to write; the other ``formats`` go beside it (same name, their suffix).
        max_panels: most panels along a third varying axis.
        formats: file formats written.

    Returns:
        ``path``.
    """
    fig = sweep_plot_figure(result, index, max_panels)
    path = Path(path)
    for fmt in formats:
        save_figure(fig, path.with_suffix("." + fmt), dpi=150, bbox_inches="tight")
    return path


def sweep_plot_figure(result: SweepResult, index: str, max_panels: int = 6) -> Figure:
    """The matplotlib ``Figure`` :func:`plot_sweep` saves."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..sweep.results import AXES

    values = result.index(index)
    grid = result.grid
    varying = [i for i, n in enumerate(grid.shape) if n > 1]
    pair = [0, 1] if 0 in varying and 1 in varying else varying[:2]
    rest = [i for i in varying if i not in pair]
    panel_axis = rest[0] if rest and len(pair) == 2 else None
    n_panel = 1 if panel_axis is None else grid.shape[panel_axis]
    picks = np.unique(np.linspace(0, n_panel - 1, min(n_panel, max_panels)).round().astype(int))
    polar = pair == [0, 1]
    cols = min(len(picks), 3)
    rows = math.ceil(len(picks) / cols)
    fig = Figure(figsize=(3.8 * cols + 1.4, 3.9 * rows + 0.5), layout="constrained")
    FigureCanvasAgg(fig)
    finite = values[np.isfinite(values)]
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    label = index_label(index, result.task)
    mesh = None
    for p, pick in enumerate(picks):
        ax = fig.add_subplot(rows, cols, p + 1, projection="polar" if polar else None)
        index_tuple = [0] * 5
        if panel_axis is not None:
            index_tuple[panel_axis] = pick
        data = values[tuple(slice(None) if i in pair else index_tuple[i] for i in range(5))]
        if len(pair) == 2:
            x, y = getattr(grid, AXES[pair[0]]), getattr(grid, AXES[pair[1]])
            if polar:
                mesh = _polar_panel(ax, np.asarray(x, float), np.asarray(y, float), data, vmin, vmax)
            else:
                mesh = ax.pcolormesh(x, y, data.T, shading="nearest", vmin=vmin, vmax=vmax)
                ax.set_xlabel(AXIS_LABELS[AXES[pair[0]]])
                ax.set_ylabel(AXIS_LABELS[AXES[pair[1]]])
        elif len(pair) == 1:
            ax.plot(getattr(grid, AXES[pair[0]]), data, marker=".")
            ax.set_xlabel(AXIS_LABELS[AXES[pair[0]]])
            ax.set_ylabel(label)
        else:
            ax.bar([index], [float(data)])
            ax.set_ylabel(label)
        if panel_axis is not None:
            caption = f"{AXIS_LABELS[AXES[panel_axis]]} = {getattr(grid, AXES[panel_axis])[pick]:g}"
            ax.set_title(caption, fontsize=9, pad=16 if polar else 6)
    if mesh is not None:
        fig.colorbar(mesh, ax=fig.axes, label=label, shrink=0.8, pad=0.12 if polar else 0.05)
    fixed = [
        f"{AXIS_LABELS[AXES[i]]} {getattr(grid, AXES[i])[0]:g}"
        for i in range(5)
        if i not in pair and i != panel_axis and grid.shape[i] > 1
    ]
    title = f"{result.spec.robot}, {result.task} task"
    if fixed:
        title += "; at " + ", ".join(fixed)
    fig.suptitle(title, fontsize=10)
    return fig


def grid_ticks(values: np.ndarray, most: int = 9) -> np.ndarray:
    """Tick positions on a grid's own values: every k-th of them (sorted, unique), the smallest k
    that leaves at most ``most`` ticks."""
    values = np.unique(np.asarray(values, dtype=float))
    step = max(1, math.ceil(len(values) / most))
    return values[::step]


def _polar_panel(ax, angles_deg: np.ndarray, distances: np.ndarray, data: np.ndarray, vmin: float, vmax: float):
    """A heat map over the swept wedge: angle from up, counter-clockwise; radius the distance."""
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(1)
    mesh = ax.pcolormesh(np.radians(angles_deg), distances, data.T, shading="nearest", vmin=vmin, vmax=vmax)
    half_a = 0.5 * float(np.min(np.diff(np.sort(angles_deg)))) if len(angles_deg) > 1 else 0.0
    half_d = 0.5 * float(np.min(np.diff(np.sort(distances)))) if len(distances) > 1 else 0.0
    lo, hi = float(angles_deg.min()) - half_a, float(angles_deg.max()) + half_a
    if hi - lo < 360.0 - 1e-9:
        ax.set_thetamin(lo)
        ax.set_thetamax(hi)
    ax.set_thetagrids(grid_ticks(angles_deg))  # on the swept angles, not matplotlib's own steps
    ax.set_rorigin(0.0)
    ax.set_rlim(max(float(distances.min()) - half_d, 0.0), float(distances.max()) + half_d)
    ax.tick_params(labelsize=8)
    ax.set_xlabel(f"angle: {AXIS_LABELS['angle_deg']}; radius: {AXIS_LABELS['distance']}", fontsize=9)
    ax.grid(True, lw=0.4)
    if hi - lo >= 360.0 - 1e-9:  # no edge to put the radial labels beside: keep them readable over the data
        ax.set_rlabel_position(lo + 22.5)
        for label in ax.get_yticklabels():
            label.set_bbox({"facecolor": "white", "alpha": 0.75, "lw": 0, "pad": 1})
    return mesh
