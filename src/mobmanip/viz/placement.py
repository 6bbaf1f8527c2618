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


def collapsed_note(ellipsoid: Ellipsoid, unit: str) -> str | None:
    """Why an objective's ellipsoid has collapsed (empty, or its smallest semi-axis below
    :data:`mobmanip.analysis.plausibility.COLLAPSED_RATIO` times its largest: a singular
    posture), or ``None``."""
    from ..analysis.plausibility import collapsed

    if ellipsoid.empty:
        return "the set is empty: the limits cannot hold the load still"
    if not collapsed(ellipsoid):
        return None
    semi = np.asarray(ellipsoid.semi_axes, dtype=float)
    return (
        f"the set has collapsed: smallest semi-axis {semi[-1]:.2g} {unit} against a largest of "
        f"{semi[0]:.3g} {unit} (a singular posture)"
    )


def _vertical(objective, task: str) -> bool:
    """Whether the objective looks along a mostly vertical direction (then a side view shows it)."""
    from ..robot.tasks import get_task

    if objective.direction is None:
        return False
    space = get_task(task)
    d = np.zeros(3)
    for i in space.linear_rows:
        d[space.rows[i]] = objective.direction[i]
    return bool(abs(d[2]) > np.linalg.norm(d[:2]))


def placement_top_figure(
    robot: Robot,
    placement: Placement,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
) -> Figure:
    """The figure of a :class:`mobmanip.placement.Placement` (see :func:`placement_figure`)."""
    from .figures import draw_ellipse, draw_robot, plt
    from .labels import mathtext, objective_unit, objective_words

    objective = placement.objective
    panels = []
    for caption, q, value in (
        ("best start", placement.start_q, placement.start_value),
        ("optimum", placement.q, placement.value),
    ):
        if q is not None:
            analysis = analyze(robot, q, task, object_mass=object_mass, decoupled=decoupled)
            ellipsoid = cast(Ellipsoid, analysis.measures[objective.ellipsoid])  # objectives are of ellipsoids
            panels.append((caption, value, q, ellipsoid, analysis))
    task_name = panels[-1][4].task
    unit = mathtext(_quantity_unit(objective.ellipsoid))
    value_unit = objective_unit(objective, task_name)
    side = _vertical(objective, task_name)
    largest = max((float(p[3].semi_axes[0]) for p in panels if not p[3].empty), default=1.0)
    scale = 0.6 / largest if largest > 0 else 1.0
    fig, axes = plt.subplots(
        1, len(panels), figsize=(max(5.2 * len(panels), 7.5), 5.6), squeeze=False, layout="constrained"
    )
    for ax, (caption, value, q, ellipsoid, analysis) in zip(axes[0], panels):
        point = analysis.held_object.center
        if side:
            points = _draw_side(ax, robot, q, ellipsoid, analysis, scale, objective.ellipsoid)
        else:
            draw_robot(ax, robot, q)
            points = [np.asarray(q[:2])[None], np.asarray(point[:2])[None]]
            if not ellipsoid.empty:
                points.append(
                    draw_ellipse(
                        ax, ellipsoid, point, scale, color="#009E73", lw=1.8, label=f"{objective.ellipsoid} ellipsoid"
                    )
                )
            ax.plot(*point[:2], "k+", ms=12, zorder=5, label="object")
        everything = np.vstack(points)
        middle = 0.5 * (everything.min(axis=0) + everything.max(axis=0))
        span = float(np.max(everything.max(axis=0) - everything.min(axis=0))) + (0.6 if side else 2.0)
        ax.set_xlim(middle[0] - span / 2, middle[0] + span / 2)
        ax.set_ylim(middle[1] - span / 2, middle[1] + span / 2)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, lw=0.3)
        if side:
            ax.set_xlabel("$s$: horizontal, from the platform towards the object (m)")
            ax.set_ylabel("$z$ (m)")
        else:
            ax.set_xlabel("$x$ (m)")
            ax.set_ylabel("$y$ (m)")
        ax.set_title(f"{caption}: {value:.4g} ({value_unit})")
        note = collapsed_note(ellipsoid, unit)
        if note is not None:
            ax.text(0.02, 0.02, note.replace(": ", ":\n", 1), transform=ax.transAxes, fontsize=7.5, color="#D55E00",
                    va="bottom", ha="left", wrap=True)  # fmt: skip
    handles, labels = axes[0, -1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 4), fontsize=8, frameon=False)
    x, y, heading = placement.platform
    target = ", ".join(f"{v:g}" for v in placement.target)
    view = "side view" if side else "from above"
    fig.suptitle(
        f"{robot.name}: {objective_words(objective, task_name)}, object at ({target}) m, {view}\n"
        f"ellipse scale: 1 {unit} = {scale:.3g} m; optimum: platform $x$ {x:.3f} m, $y$ {y:.3f} m, "
        f"heading {math.degrees(heading):.1f}\N{DEGREE SIGN}",
        fontsize=10,
    )
    return fig


def _quantity_unit(name: str) -> str:
    from ..measures import get_measure

    return get_measure(name).quantity.unit


def _draw_side(
    ax, robot: Robot, q: np.ndarray, ellipsoid: Ellipsoid, analysis, scale: float, ellipsoid_name: str
) -> list[np.ndarray]:
    """A side view in the vertical plane through the platform centre and the object: the floor,
    the platform's footprint along that plane, the arms (joints and end effectors) and the
    shadow of the set on the plane at the object. Returns the drawn points (k, 2)."""
    import pinocchio as pin

    from .figures import ARM_COLORS, arm_label, draw_ellipse
    from .shapes import drawn_linear_part

    point = np.asarray(analysis.held_object.center, dtype=float)
    origin = np.asarray(q[:2], dtype=float)
    toward = point[:2] - origin
    h = toward / np.linalg.norm(toward) if np.linalg.norm(toward) > 1e-9 else np.array([q[2], q[3]], dtype=float)

    def plane(p: np.ndarray) -> np.ndarray:
        return np.array([(np.asarray(p[:2]) - origin) @ h, p[2]])

    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, q)
    drawn = [np.array([[0.0, 0.0]]), plane(point)[None]]
    ax.axhline(0.0, color="0.3", lw=1.0, zorder=1)
    ax.plot([-0.3, 0.3], [0.0, 0.0], color="0.45", lw=8, solid_capstyle="butt", zorder=1, label="platform")
    for k, arm in enumerate(robot.arms):
        chain = [data.oMi[model.getJointId(name)].translation for name in arm.joint_names]
        chain.append(data.oMf[arm.frame_id].translation)
        xy = np.array([plane(p) for p in chain])
        color = ARM_COLORS[k % len(ARM_COLORS)]
        ax.plot(xy[:, 0], xy[:, 1], "-o", color=color, lw=2.2, ms=3.5, zorder=3, label=arm_label(robot, k))
        drawn.append(xy)
    if not ellipsoid.empty:
        linear, E = drawn_linear_part(ellipsoid, analysis.task)
        linear = cast(Ellipsoid, linear)
        P = np.array([[h[0], h[1], 0.0], [0.0, 0.0, 1.0]]) @ E  # world directions onto (s, z)
        shadow = Ellipsoid.from_generator(P @ linear.center, P @ linear.generator)
        at = plane(point)
        drawn.append(
            draw_ellipse(
                ax,
                shadow,
                at,
                scale,
                color="#009E73",
                lw=1.8,
                label=f"{ellipsoid_name} ellipsoid (its shadow on the view)",
            )
        )
    ax.plot(*plane(point), "k+", ms=12, zorder=5, label="object")
    return drawn


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
    there is one, then the optimum -- with the robot (:func:`mobmanip.viz.figures.draw_robot`),
    the object (+) and the objective's ellipsoid at the object, on one scale (the largest
    semi-axis drawn 0.6 m long). Seen from above, or from the side (the vertical plane through
    the platform and the object) when the objective looks along a mostly vertical direction.
    Each panel's title gives the objective's value with its unit; a set that has collapsed (a
    singular posture, :func:`collapsed_note`) is said so in its panel. One legend below the panels.
    """
    from .figures import save_and_close

    fig = placement_top_figure(robot, placement, task, object_mass=object_mass, decoupled=decoupled)
    return save_and_close(fig, path, dpi=110, bbox_inches="tight")


#: The map figure's layout, inches: the sides of the map's box (the longer one the largest; the
#: shorter one at least the least, the data's limits widened to keep their aspect), and the
#: margins around it (tick labels and axis label on the left and below, the colour bar and its
#: label on the right, the legend under the x axis label, the title's lines above).
MAP_BOX, MAP_BOX_LEAST, MAP_LEFT, MAP_BOTTOM, MAP_LEGEND, MAP_TITLE_LINE = 4.6, 3.0, 0.85, 0.62, 0.3, 0.19
MAP_BAR_GAP, MAP_BAR_WIDTH, MAP_BAR_LABELS = 0.2, 0.22, 0.85


def placement_map_figure(placement_map: PlacementMap, title: str | None = None) -> Figure:
    """A heat map of a :class:`mobmanip.placement.maps.PlacementMap`'s best value over headings,
    arrows for the best heading, the object (star) and the best cell (circle); the colour bar
    names the objective with its unit, the legend stands below the map.

    The layout is set here, in inches (:data:`MAP_BOX` and the margins after it): the map's box
    has the grid's aspect, its longer side :data:`MAP_BOX`, and the page is sized around it. No
    layout engine runs when the figure is drawn, and it is drawn once when written (a layout
    engine and a cropped page draw it twice): the command writes this figure with every map.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..robot.tasks import get_task
    from .labels import objective_label, objective_words

    grid = placement_map
    task = grid.task or _task_of(grid.objective)
    values, heading = grid.best_over_headings()
    fig = Figure()
    FigureCanvasAgg(fig)  # drawn and written without pyplot
    ax = fig.add_subplot()
    masked = np.ma.masked_invalid(values)
    mesh = ax.pcolormesh(grid.x, grid.y, masked, shading="nearest", cmap="viridis")
    ok = ~np.isnan(values)
    X, Y = np.meshgrid(grid.x, grid.y)
    step = max(1, max(len(grid.x), len(grid.y)) // 15)
    sel = np.zeros_like(ok)
    sel[::step, ::step] = True
    sel &= ok
    ax.quiver(X[sel], Y[sel], np.cos(heading[sel]), np.sin(heading[sel]), color="white", scale=25, width=0.004,
              label="best heading")  # fmt: skip
    ax.plot(*grid.target[:2], marker="*", color="red", markersize=14, linestyle="none", label="object")
    if ok.any():
        _, q, _ = grid.best()
        ax.plot(q[0], q[1], marker="o", markerfacecolor="none", markeredgecolor="red", markersize=12,
                linestyle="none", label="best platform position")  # fmt: skip
    ax.set_xlabel("platform $x$ (m)")
    ax.set_ylabel("platform $y$ (m)")
    ax.set_aspect("equal")
    # the box at the data's aspect (within its least and largest sides), on a page sized around it
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    ratio = (y1 - y0) / (x1 - x0)
    width, height = (MAP_BOX, MAP_BOX * ratio) if ratio <= 1.0 else (MAP_BOX / ratio, MAP_BOX)
    if min(width, height) < MAP_BOX_LEAST:  # a strip: the limits widen along its short side instead
        width, height = max(width, MAP_BOX_LEAST), max(height, MAP_BOX_LEAST)
        ax.set_aspect("equal", adjustable="datalim")
    lines = _title_lines(fig, title or f"best {objective_words(grid.objective, task)} over heading and posture", width)
    page_width = MAP_LEFT + width + MAP_BAR_GAP + MAP_BAR_WIDTH + MAP_BAR_LABELS
    bottom = MAP_BOTTOM + MAP_LEGEND
    page_height = bottom + height + 0.12 + MAP_TITLE_LINE * len(lines)
    fig.set_size_inches(page_width, page_height)
    ax.set_position((MAP_LEFT / page_width, bottom / page_height, width / page_width, height / page_height))
    cax = fig.add_axes(((MAP_LEFT + width + MAP_BAR_GAP) / page_width, bottom / page_height,
                        MAP_BAR_WIDTH / page_width, height / page_height), label="<colorbar>")  # fmt: skip
    fig.colorbar(mesh, cax=cax, label=objective_label(grid.objective, get_task(task)))
    ax.set_title("\n".join(lines), fontsize=10)
    handles, labels = ax.get_legend_handles_labels()
    # the arrows are white on the heat map: on the white page their legend entry is an arrow in grey
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color="0.3", marker=r"$\rightarrow$", markersize=12, linestyle="none")
               if label == "best heading" else handle for handle, label in zip(handles, labels)]  # fmt: skip
    labels = ["best heading (white arrows)" if label == "best heading" else label for label in labels]
    fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=3, fontsize=8,
               frameon=False)  # fmt: skip
    return fig


def _title_lines(fig: Figure, text: str, width: float) -> list[str]:
    """``text`` in as few lines as keep each within ``width`` inches (10 pt, measured)."""
    import textwrap

    from matplotlib.text import Text

    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    probe = Text(0, 0, "", fontsize=10, figure=fig)

    def inches(line: str) -> float:
        probe.set_text(line)
        return probe.get_window_extent(renderer).width / fig.dpi

    chars = len(text)
    lines = [text]
    while chars > 12 and max(map(inches, lines)) > width:
        chars = int(chars * 0.85)
        lines = textwrap.wrap(text, chars)
    return lines


def _task_of(objective) -> str:
    """A task for an objective's labels when none was recorded: by the direction's length."""
    if objective.direction is None:
        return "translational"
    return {2: "planar", 3: "translational", 6: "spatial"}.get(len(objective.direction), "translational")


def plot_placement_map(placement_map: PlacementMap, path: str | Path, title: str | None = None) -> Path:
    """Write :func:`placement_map_figure` (PNG or SVG by the file's suffix) atomically; returns the path.

    Written through the figure's own canvas: neither pyplot nor :mod:`mobmanip.viz.figures` is
    imported (``place --map`` writes this figure and no other)."""
    from ..support.files import save_figure

    return save_figure(placement_map_figure(placement_map, title), path, dpi=110)
