"""Top-view figures of a planar mobile manipulator with its task-space ellipses (matplotlib).

Ellipses are drawn at the task point in metres after multiplying their semi-axes by a scale
(e.g. 0.2 m per m/s); the scale is printed in each figure's title.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # figures are written to files; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from ..ellipsoids import Ellipsoid  # noqa: E402
from ..io import save_figure  # noqa: E402
from ..model import Robot  # noqa: E402

COLORS = ("#1b9e77", "#d95f02", "#7570b3", "#444444", "#e7298a", "#66a61e")


def _platform_outline(robot: Robot) -> np.ndarray:
    """Corners (k, 2) of the platform body in its own frame (the platform kind draws it)."""
    platform = robot.wheel_platform if robot.wheel_platform is not None else robot.platform
    return platform.outline()


def draw_robot(ax, robot: Robot, q: np.ndarray) -> None:
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


def draw_ellipse(ax, ellipse: Ellipsoid, at: np.ndarray, scale: float, **style) -> None:
    """Draw a 2-D ellipse (task units) at a point (m), semi-axes multiplied by ``scale``."""
    if ellipse.dim != 2:
        ellipse = ellipse.project((0, 1))
    shifted = Ellipsoid.from_generator(np.asarray(at[:2]) + scale * ellipse.center, scale * ellipse.generator)
    points = shifted.boundary(240)
    ax.plot(points[:, 0], points[:, 1], zorder=4, **style)


def sweep_figure(
    panels: Sequence[tuple[str, Robot, np.ndarray, np.ndarray, Sequence[tuple[str, Ellipsoid]]]],
    title: str,
    unit: str,
    path: str | Path,
    scale: float | None = None,
) -> float:
    """One panel per configuration, each with the robot and nested ellipses at the task point.

    Args:
        panels: per panel (caption, robot, q, task point (m), [(legend label, ellipse[, style]), ...]),
            where the optional style is a dict of matplotlib line properties.
        title: figure title.
        unit: unit of the ellipses (e.g. "m/s").
        path: PNG file to write.
        scale: metres drawn per task unit; by default the largest semi-axis becomes 0.9 m.

    Returns:
        The scale used (m per task unit).
    """
    if scale is None:
        largest = max(float(entry[1].semi_axes[0]) for *_, entries in panels for entry in entries)
        scale = 0.9 / largest if largest > 0 else 1.0
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 5.4), squeeze=False)
    for ax, (caption, robot, q, point, ellipses) in zip(axes[0], panels):
        draw_robot(ax, robot, q)
        for k, (label, ellipse, *style) in enumerate(ellipses):
            look = {"color": COLORS[k % len(COLORS)], "lw": 1.8, **(style[0] if style else {})}
            draw_ellipse(ax, ellipse, point, scale, label=label, **look)
        ax.plot(*point[:2], "k+", ms=10, zorder=5)
        ax.set_title(caption)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlim(-1.0, 2.2)
        ax.set_ylim(-1.0, 2.2)
        ax.grid(True, lw=0.3)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(loc="lower right", fontsize=8)
    fig.suptitle(f"{title}  (ellipse scale: 1 {unit} = {scale:.3g} m)")
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
    return scale
