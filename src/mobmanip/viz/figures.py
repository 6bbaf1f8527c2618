"""Top-view figures of a planar mobile manipulator with its task-space sets (matplotlib).

Ellipses (and the outlines of capacity polytopes) are drawn at the task point in metres after
multiplying them by a scale (e.g. 0.2 m per m/s); the scale is printed in each figure's title.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # figures are written to files; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from ..ellipsoids import Ellipsoid  # noqa: E402
from ..io import save_figure  # noqa: E402
from ..model import Robot  # noqa: E402
from ..polytope import Polytope  # noqa: E402

COLORS = ("#1b9e77", "#d95f02", "#7570b3", "#444444", "#e7298a", "#66a61e")


def _platform_outline(robot: Robot) -> np.ndarray:
    """Corners (k, 2) of the platform body in its own frame (the platform kind draws it)."""
    platform = robot.wheel_platform if robot.wheel_platform is not None else robot.platform
    return platform.outline()


def draw_robot(ax: Axes, robot: Robot, q: np.ndarray) -> None:
    """Draw the platform, its wheels and the arms (links as lines through the joints) from above."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, q)
    yaw = float(np.arctan2(q[3], q[2]))
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    origin = np.asarray(q[:2])
    body = _platform_outline(robot) @ R.T + origin
    ax.add_patch(Polygon(body, closed=True, facecolor="#d9d9d9", edgecolor="#555555", lw=1.0, zorder=1))
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
        ax.plot(*np.array([centre - tip, centre + tip]).T, color="black", lw=5, solid_capstyle="butt", zorder=2)
    for k, arm in enumerate(robot.arms):
        points = [data.oMi[model.getJointId(name)].translation[:2] for name in arm.joint_names]
        points.append(data.oMf[arm.frame_id].translation[:2])
        points = np.array(points)
        ax.plot(points[:, 0], points[:, 1], "-o", color=("#c05a1f", "#3a6fb0")[k % 2], lw=2.5, ms=4, zorder=3)


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


def _extent(task_set) -> float:
    """How far a set is drawn from the task point (task units): the largest semi-axis of an
    ellipse (centred there in the paper's horizontal tasks), the farthest vertex of a polygon."""
    if task_set.empty:
        return 0.0
    if task_set.kind == "ellipsoid":
        return float(task_set.semi_axes[0])
    flat = task_set if task_set.dim == 2 else task_set.project((0, 1))
    return float(np.max(np.linalg.norm(flat.vertices, axis=1), initial=0.0))


def sweep_figure(
    panels: Sequence[tuple[str, Robot, np.ndarray, np.ndarray, Sequence[tuple]]],
    title: str,
    unit: str,
    path: str | Path,
    scale: float | None = None,
    drawn: list | None = None,
    note: str = "",
    legend_loc: str = "lower right",
) -> float:
    """One panel per configuration, each with the robot and nested sets at the task point.

    Args:
        panels: per panel (caption, robot, q, task point (m), [(legend label, set[, style]), ...]),
            where a set is an ellipse or a polytope (drawn as its outline) and the optional style
            is a dict of matplotlib line properties; a label starting with ``_`` is left out of
            the legend.
        title: figure title.
        unit: unit of the sets (e.g. "m/s").
        path: PNG file to write.
        scale: metres drawn per task unit; by default the largest extent (an ellipse's largest
            semi-axis, a polygon's farthest vertex) becomes 0.9 m.
        drawn: if given, a record of each curve drawn is appended to it: a dict with
            ``panel`` (index), ``caption``, ``label``, ``kind`` (the set's), ``point`` (the task
            point (2,), m), ``scale`` and ``points`` (k, 2), m: an ellipse's boundary points or a
            polygon's vertices.
        note: a second title line (e.g. what the line styles mean).
        legend_loc: where matplotlib puts each panel's legend.

    Returns:
        The scale used (m per task unit).
    """
    if scale is None:
        largest = max(_extent(entry[1]) for *_, entries in panels for entry in entries)
        scale = 0.9 / largest if largest > 0 else 1.0
    polygons = any(entry[1].kind != "ellipsoid" for *_, entries in panels for entry in entries)
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 5.4 + 0.3 * bool(note)), squeeze=False)
    for index, (ax, (caption, robot, q, point, sets)) in enumerate(zip(axes[0], panels)):
        draw_robot(ax, robot, q)
        low, high = np.array([-1.0, -1.0]), np.array([2.2, 2.2])
        top = -np.inf
        for k, (label, task_set, *style) in enumerate(sets):
            look = {"color": COLORS[k % len(COLORS)], "lw": 1.8, **(style[0] if style else {})}
            draw = draw_ellipse if task_set.kind == "ellipsoid" else draw_polygon
            points = draw(ax, task_set, point, scale, label=label, **look)
            if len(points):
                low, high = np.minimum(low, points.min(axis=0) - 0.1), np.maximum(high, points.max(axis=0) + 0.1)
                top = max(top, float(points[:, 1].max()))
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
                    }
                )
        if legend_loc.startswith("upper"):  # room above the sets for the legend
            high[1] = max(high[1], top + 0.6)
        ax.plot(*point[:2], "k+", ms=10, zorder=5)
        ax.set_title(caption)
        ax.set_aspect("equal", adjustable="box")
        side = float(np.max(high - low))  # a square view holding every set
        middle = 0.5 * (low + high)
        ax.set_xlim(middle[0] - side / 2, middle[0] + side / 2)
        ax.set_ylim(middle[1] - side / 2, middle[1] + side / 2)
        ax.grid(True, lw=0.3)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(loc=legend_loc, fontsize=8)
    what = "scale" if polygons else "ellipse scale"
    heading = f"{title}  ({what}: 1 {unit} = {scale:.3g} m)"
    fig.suptitle(f"{heading}\n{note}" if note else heading)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
    return scale
