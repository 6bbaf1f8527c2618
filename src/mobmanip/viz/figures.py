"""Top-view figures of a planar mobile manipulator with its task-space sets (matplotlib), made
to go into a paper as they are.

Ellipses (and the outlines of capacity polytopes) are drawn at the task point in metres after
multiplying them by a scale (e.g. 0.2 m per m/s), stated under the panels. Sets use the
colour-blind-safe Okabe-Ito palette (:data:`SET_COLORS`); the arms are drawn in greys
(:data:`ARM_COLORS`), never in a set's colour, and named in the legend; the platform carries an
arrow along its heading. One legend for the figure, outside the panels; sets of a panel that
coincide (the same support in every direction, within :data:`COINCIDE_RTOL`) are drawn once
(the last of them, which would be on top) and a note says so. Every panel of a figure has the
same metres per inch, and panels of twin figures (e.g. Fig. 4 and its coupled counterpart) can
share their axis limits (:func:`panel_limits`). Each figure is written as PNG and as vector PDF (``formats``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import matplotlib

matplotlib.use("Agg")  # figures are written to files; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.patches import FancyArrow, Polygon  # noqa: E402

from ..robot.model import Robot
from ..sets.ellipsoid import Ellipsoid
from ..sets.polytope import Polytope
from ..sets.taskset import TaskSet
from ..support.files import save_figure

#: The Okabe-Ito palette (colour-blind safe), by name.
OKABE_ITO = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
}
#: Colours of the sets, in order (Okabe-Ito; yellow left out: too light on white).
SET_COLORS = tuple(OKABE_ITO[k] for k in ("blue", "vermillion", "bluish_green", "reddish_purple", "orange", "sky_blue"))
COLORS = SET_COLORS  # the former name
#: Colours of the arms (greys, so that no arm looks like a set).
ARM_COLORS = ("#4a4a4a", "#9a9a9a")
PLATFORM_FACE, PLATFORM_EDGE = "#e6e6e6", "#6e6e6e"
#: Sets of a panel whose supports differ by at most this fraction of the larger are drawn once.
COINCIDE_RTOL = 2e-3
#: Margin around a panel's content (fraction of its span).
PAD = 0.06
FORMATS = ("png", "pdf")


def save_and_close(fig: Any, path: str | Path, **options: Any) -> Path:
    """Save ``fig`` (:func:`mobmanip.support.files.save_figure`: atomically, in the format its
    suffix names; ``options`` go to ``savefig``) and close it, saved or not; returns the path."""
    try:
        save_figure(fig, path, **options)
    finally:
        plt.close(fig)
    return Path(path)


def _platform_outline(robot: Robot) -> np.ndarray:
    """Corners (k, 2) of the platform body in its own frame (the platform kind draws it)."""
    platform = robot.wheel_platform if robot.wheel_platform is not None else robot.platform
    return platform.outline()


def arm_label(robot: Robot, k: int) -> str:
    """Legend label of arm ``k``: ``arm 1 (right)``."""
    name = robot.arms[k].name
    return f"arm {k + 1}" + (f" ({name})" if name and name != str(k + 1) else "")


def robot_points(robot: Robot, q: np.ndarray) -> np.ndarray:
    """What :func:`draw_robot` draws, as points (k, 2), m: the platform's corners, the joints
    and the end effectors."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, q)
    yaw = float(np.arctan2(q[3], q[2]))
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    points = [_platform_outline(robot) @ R.T + np.asarray(q[:2])]
    for arm in robot.arms:
        points.append([data.oMi[model.getJointId(name)].translation[:2] for name in arm.joint_names])
        points.append([data.oMf[arm.frame_id].translation[:2]])
    return np.vstack(points)


def draw_robot(ax: Axes, robot: Robot, q: np.ndarray, label_arms: bool = True, who: str = "") -> None:
    """Draw the platform with an arrow along its heading, its wheels and the arms (links as
    lines through the joints, in greys, labelled ``arm 1 (right)``, ... for the legend, after
    ``who``: ``north: arm 1 (right)`` in a figure of several robots) from above."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, q)
    yaw = float(np.arctan2(q[3], q[2]))
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    origin = np.asarray(q[:2], dtype=float)
    outline = _platform_outline(robot)
    body = outline @ R.T + origin
    ax.add_patch(Polygon(body, closed=True, facecolor=PLATFORM_FACE, edgecolor=PLATFORM_EDGE, lw=0.8, zorder=1))
    length = 0.8 * float(np.max(outline[:, 0]))  # the arrow reaches most of the way to the front
    if length > 0:
        heading = R[:, 0] * length
        ax.add_patch(
            FancyArrow(
                *origin,
                *heading,
                width=0.012,
                head_width=0.06,
                head_length=0.06,
                length_includes_head=True,
                color="black",
                lw=0,
                zorder=2,
            )
        )
    platform = robot.wheel_platform
    wheels = platform.wheels() if platform is not None else ()
    if wheels:
        pin.computeJointJacobians(model, data, q)
    for name, radius in wheels:  # a segment along the wheel's rolling direction, as long as its diameter
        joint_id = model.getJointId(name)
        axle = pin.getJointJacobian(model, data, joint_id, pin.LOCAL_WORLD_ALIGNED)[3:, model.joints[joint_id].idx_v]
        rolling = np.cross(axle, (0.0, 0.0, 1.0))[:2]
        tip = radius * rolling / max(float(np.linalg.norm(rolling)), 1e-12)
        centre = data.oMi[joint_id].translation[:2]
        ax.plot(*np.array([centre - tip, centre + tip]).T, color="black", lw=4, solid_capstyle="butt", zorder=2)
    for k, arm in enumerate(robot.arms):
        points = [data.oMi[model.getJointId(name)].translation[:2] for name in arm.joint_names]
        points.append(data.oMf[arm.frame_id].translation[:2])
        points = np.array(points)
        label = f"{who}: {arm_label(robot, k)}" if who else arm_label(robot, k)
        label = label if label_arms else "_arm"
        color = ARM_COLORS[k % len(ARM_COLORS)]
        ax.plot(points[:, 0], points[:, 1], "-o", color=color, lw=2.2, ms=3.5, zorder=3, label=label)


def draw_ellipse(ax: Axes, ellipse: Ellipsoid, at: np.ndarray, scale: float, **style: Any) -> np.ndarray:
    """Draw a 2-D ellipse (task units) at a point (m), semi-axes multiplied by ``scale``;
    returns the drawn boundary points (k, 2) in metres."""
    if ellipse.dim != 2:
        ellipse = ellipse.project((0, 1))
    shifted = Ellipsoid.from_generator(np.asarray(at[:2]) + scale * ellipse.center, scale * ellipse.generator)
    points = shifted.boundary(240)
    ax.plot(points[:, 0], points[:, 1], zorder=4, **style)
    return points


def draw_polygon(ax: Axes, polytope: Polytope, at: np.ndarray, scale: float, **style: Any) -> np.ndarray:
    """Draw a 2-D polytope (task units; its shadow on the first two coordinates otherwise) at a
    point (m), multiplied by ``scale``, as its closed outline; returns the drawn vertices (k, 2)
    in metres, counter-clockwise (none when empty)."""
    if polytope.dim != 2:
        polytope = polytope.project((0, 1))
    if polytope.empty:
        return np.zeros((0, 2))
    points = np.asarray(at[:2]) + scale * polytope.vertices
    closed = np.vstack([points, points[:1]])
    ax.plot(closed[:, 0], closed[:, 1], zorder=4, **style)
    return points


def extent(task_set: Ellipsoid | Polytope) -> float:
    """How far a set is drawn from the task point (task units): the largest semi-axis of an
    ellipse (centred there in the paper's horizontal tasks), the farthest vertex of a polygon."""
    if task_set.empty:
        return 0.0
    if isinstance(task_set, Ellipsoid):
        return float(task_set.semi_axes[0])
    flat = task_set if task_set.dim == 2 else task_set.project((0, 1))
    return float(np.max(np.linalg.norm(flat.vertices, axis=1), initial=0.0))


_DIRECTIONS = np.column_stack(
    [np.cos(np.linspace(0, 2 * np.pi, 90, endpoint=False)), np.sin(np.linspace(0, 2 * np.pi, 90, endpoint=False))]
)


def support(task_set: TaskSet, directions: np.ndarray = _DIRECTIONS) -> np.ndarray:
    """Support function of the drawn (x, y) part of a set along unit ``directions`` (k, 2):
    ``max <d, x>`` over the set, task units; ``-inf`` for an empty set."""
    if task_set.empty:
        return np.full(len(directions), -np.inf)
    flat = task_set if task_set.dim == 2 else task_set.project((0, 1))
    if isinstance(flat, Ellipsoid):
        return directions @ flat.center + np.linalg.norm(directions @ flat.generator, axis=1)
    return np.max(directions @ cast(Polytope, flat).vertices.T, axis=1)


def coincide(a: TaskSet, b: TaskSet, rtol: float = COINCIDE_RTOL) -> bool:
    """Whether two sets draw the same curve: supports within ``rtol`` of the larger set's reach."""
    ha, hb = support(a), support(b)
    if not (np.all(np.isfinite(ha)) and np.all(np.isfinite(hb))):
        return bool(a.empty and b.empty)
    reach = max(float(np.max(np.abs(ha))), float(np.max(np.abs(hb))), 1e-300)
    return bool(np.max(np.abs(ha - hb)) <= rtol * reach)


def scale_of(panels: Sequence) -> float:
    """The drawing scale (figure units per task unit) at which the largest set of ``panels`` fills 0.9."""
    largest = max(extent(entry[1]) for *_, entries in panels for entry in entries)
    return 0.9 / largest if largest > 0 else 1.0


def panel_bounds(panels: Sequence[tuple], scale: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """(lower (2,), upper (2,)), m, of what each panel draws: the robot and its sets at ``scale``."""
    bounds = []
    for _, robot, q, point, sets in panels:
        points = [robot_points(robot, q), np.asarray(point[:2], dtype=float)[None]]
        for _, task_set, *_ in sets:
            if not task_set.empty:
                h = support(task_set, np.vstack([np.eye(2), -np.eye(2)]))
                points.append(np.asarray(point[:2]) + scale * np.array([[h[0], h[1]], [-h[2], -h[3]]]))
        points = np.vstack(points)
        bounds.append((points.min(axis=0), points.max(axis=0)))
    return bounds


def panel_limits(
    *bounds: list[tuple[np.ndarray, np.ndarray]], pad: float = PAD
) -> list[tuple[tuple[float, float], ...]]:
    """Axis limits ((x0, x1), (y0, y1)) per panel: each panel's content (the union over the given
    figures' :func:`panel_bounds`, panel by panel) centred in a box as wide and as tall as the
    widest and tallest content of any panel, plus ``pad``. Every panel thus shows the same
    metres per inch, and figures given together get the same limits."""
    joined = [
        (np.min([b[i][0] for b in bounds], axis=0), np.max([b[i][1] for b in bounds], axis=0))
        for i in range(len(bounds[0]))
    ]
    span = np.max([hi - lo for lo, hi in joined], axis=0) * (1.0 + 2.0 * pad)
    limits = []
    for lo, hi in joined:
        middle = 0.5 * (lo + hi)
        limits.append(tuple((float(middle[i] - span[i] / 2), float(middle[i] + span[i] / 2)) for i in range(2)))
    return limits


def sweep_figure(
    panels: Sequence[tuple[str, Robot, np.ndarray, np.ndarray, Sequence[tuple]]],
    title: str,
    unit: str,
    path: str | Path,
    scale: float | None = None,
    drawn: list | None = None,
    note: str = "",
    legend_loc: str = "upper center",
    limits: Sequence[tuple[tuple[float, float], ...]] | None = None,
    formats: Sequence[str] = FORMATS,
    keep: list | None = None,
) -> float:
    """One panel per configuration, each with the robot and nested sets at the task point.

    Args:
        panels: per panel (caption, robot, q, task point (m), [(legend label, set[, style]), ...]),
            where a set is an ellipse or a polytope (drawn as its outline) and the optional style
            is a dict of matplotlib line properties; a label starting with ``_`` is left out of
            the legend. Labels and captions may use mathtext (``$\\tau_{\\max}$``).
        title: figure title above the panels; empty (as for a paper, whose caption says it)
            for none.
        unit: unit of the sets, mathtext allowed (e.g. ``m/s$^2$``).
        path: the file to write (its suffix is replaced by each of ``formats``).
        scale: metres drawn per task unit; by default the largest extent (an ellipse's largest
            semi-axis, a polygon's farthest vertex) becomes 0.9 m.
        drawn: if given, a record of each set is appended to it: a dict with ``panel``
            (index), ``caption``, ``label``, ``kind`` (the set's), ``point`` (the task point (2,),
            m), ``scale``, ``points`` (k, 2), m (an ellipse's boundary points or a polygon's
            vertices) and ``coincides_with`` (the label of the set it coincides with and is drawn
            as, or ``None`` when drawn itself).
        note: a line under the panels (e.g. what the line styles mean).
        legend_loc: where the figure's legend goes, outside the panels: ``"upper center"``
            (above them) or ``"lower center"`` (below them).
        limits: axis limits per panel (see :func:`panel_limits`); by default those of
            this figure alone.
        formats: file formats written beside each other (``png``, ``pdf``, ``svg``).
        keep: if given, the figure is appended to it and left open (the caller closes it).

    Returns:
        The scale used (m per task unit).
    """
    if scale is None:
        scale = scale_of(panels)
    if limits is None:
        limits = panel_limits(panel_bounds(panels, scale))
    polygons = any(entry[1].kind != "ellipsoid" for *_, entries in panels for entry in entries)
    (x0, x1), (y0, y1) = limits[0]
    width = 3.3 * len(panels)
    fig, axes = plt.subplots(
        1,
        len(panels),
        figsize=(width, width / len(panels) * (y1 - y0) / (x1 - x0) + 1.0),
        squeeze=False,
        layout="constrained",
    )
    notes: dict[tuple[str, str], list[str]] = {}
    for index, (ax, (caption, robot, q, point, sets)) in enumerate(zip(axes[0], panels)):
        draw_robot(ax, robot, q)
        twins: list[str | None] = [None] * len(sets)  # a set coinciding with a later one is drawn as that one
        for i in reversed(range(len(sets))):
            later = (j for j in range(i + 1, len(sets)) if twins[j] is None and coincide(sets[i][1], sets[j][1]))
            twins[i] = next((sets[j][0] for j in later), None)
        for k, (label, task_set, *style) in enumerate(sets):
            look = {"color": SET_COLORS[k % len(SET_COLORS)], "lw": 1.6, **(style[0] if style else {})}
            twin = twins[k]
            draw = draw_ellipse if task_set.kind == "ellipsoid" else draw_polygon
            if twin is None:
                points = draw(ax, task_set, point, scale, label=label, **look)
            else:  # drawn as its twin: record where it would be, and say so once
                points = _points(task_set, point, scale)
                if not label.startswith("_"):
                    notes.setdefault((label, twin), []).append(caption)
            if drawn is not None:
                drawn.append(
                    {
                        "panel": index,
                        "caption": caption,
                        "label": label,
                        "kind": task_set.kind,
                        "point": np.asarray(point[:2], dtype=float),
                        "scale": scale,
                        "points": points,
                        "coincides_with": twin,
                    }
                )
        ax.plot(*point[:2], "k+", ms=8, mew=1.0, zorder=5)
        ax.set_title(caption, fontsize=10)
        ax.set_aspect("equal", adjustable="box")
        (x0, x1), (y0, y1) = limits[index]
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.grid(True, lw=0.3, color="#dddddd")
        ax.set_xlabel("$x$ (m)")
        if index == 0:
            ax.set_ylabel("$y$ (m)")
        ax.tick_params(labelsize=8)
    handles, labels = [], []
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            if label not in labels:
                handles.append(handle)
                labels.append(label)
    what = "scale" if polygons else "ellipse scale"
    lines = [f"{what}: 1 {unit} = {scale:.3g} m"]
    for (label, twin), captions in notes.items():
        where = "every panel" if len(captions) == len(panels) else ", ".join(captions)
        lines.append(f"{label} coincides with {twin} ({where}): drawn once")
    if note:
        lines.append(note)
    fig.legend(handles, labels, loc=f"outside {legend_loc}", ncol=min(len(labels), 4), fontsize=8, frameon=False)  # type: ignore[call-overload]  # "outside ..." is built from a checked location
    fig.supxlabel("\n".join(lines), fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    try:
        for fmt in formats:
            save_figure(fig, Path(path).with_suffix("." + fmt), dpi=200)
    finally:
        if keep is None:
            plt.close(fig)
        else:
            keep.append(fig)
    return scale


def _points(task_set, at: np.ndarray, scale: float) -> np.ndarray:
    """The points :func:`draw_ellipse` / :func:`draw_polygon` would draw, without drawing them."""
    if task_set.kind == "ellipsoid":
        flat = task_set if task_set.dim == 2 else task_set.project((0, 1))
        return Ellipsoid.from_generator(np.asarray(at[:2]) + scale * flat.center, scale * flat.generator).boundary(240)
    flat = task_set if task_set.dim == 2 else task_set.project((0, 1))
    return np.zeros((0, 2)) if flat.empty else np.asarray(at[:2]) + scale * flat.vertices
