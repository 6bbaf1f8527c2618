"""Figures of motions over time: a trajectory's demands against its capacity
(``mobmanip trajectory --out``), the capacity profiles of a carried path (``mobmanip carry
--out``, ``mobmanip team-carry --out``) and the top view of a team's carried path.

Each function returns a matplotlib ``Figure``; the caller saves it
(:func:`mobmanip.support.files.save_figure`) and closes it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..coordination.carry import TeamCarryResult
    from ..motion.carry import CarryResult
    from ..motion.trajectory_analysis import TrajectoryAnalysis


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # figures are written to files; no display needed
    import matplotlib.pyplot as plt

    return plt


def trajectory_figure(result: TrajectoryAnalysis) -> Figure:
    """Three panels over time: speed against velocity capacity, acceleration against
    acceleration capacity, and the largest velocity and effort use (fractions of the limits)."""
    plt = _pyplot()
    t = result.trajectory.t
    fig, axes = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True)
    ax = axes[0]
    ax.plot(t, np.linalg.norm(result.object_velocity, axis=1), label="object speed |v_o|")
    ax.plot(t, result.velocity_capacity, label="kinematic capacity along v_o")
    if result.velocity_polytope_capacity is not None:
        ax.plot(t, result.velocity_polytope_capacity, label="kinematic polytope along v_o")
    ax.plot(t, result.kinematic_semi_axes[:, -1], "--", label="kinematic minor semi-axis")
    ax.set_ylabel("m/s (rad/s)")
    ax.legend(loc="best", fontsize=8)
    ax = axes[1]
    ax.plot(t, np.linalg.norm(result.object_acceleration, axis=1), label="object acceleration |a_o|")
    ax.plot(t, result.acceleration_capacity, label="dynamic capacity along a_o (in motion)")
    ax.set_ylabel("m/s^2 (rad/s^2)")
    ax.legend(loc="best", fontsize=8)
    ax = axes[2]
    ax.plot(t, result.velocity_use.max(axis=1), label="largest |x_i| / xdot_max_i")
    ax.plot(t, result.effort_use.max(axis=1), label="largest |tau_i| / tau_max_i")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_ylabel("fraction of limit")
    ax.set_xlabel("t (s)")
    ax.legend(loc="best", fontsize=8)
    k = result.scaling.k_max
    margin = "unbounded" if k is None else (f"{k:.3f}" if result.scaling.feasible else "none")
    fig.suptitle(f"{result.robot_name}, task {result.task}: time-scaling margin {margin}")
    fig.tight_layout()
    return fig


def carry_figure(result: CarryResult | TeamCarryResult) -> Figure:
    """The objective over time along a carried path: the self-motion before the path (when there
    is one), the QP motion with its capacity term and the weighted pseudo-inverse baseline (of
    one robot, or of a team: :func:`mobmanip.coordination.team_carry`)."""
    plt = _pyplot()
    motion, base = result.motion, result.baseline
    fig, ax = plt.subplots(figsize=(7, 3.5))
    prep = result.preparation
    if prep is not None:
        ax.plot(prep.t, prep.capacity, color="0.5", label="self-motion before the path (object held still)")
    ax.plot(motion.t, motion.capacity, label="QP with capacity term")
    ax.plot(base.t, base.capacity, label="weighted pseudo-inverse")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(result.objective.name)
    ax.legend(loc="best")
    fig.tight_layout()
    return fig


def team_carry_figure(result: TeamCarryResult, poses: int = 7) -> Figure:
    """Top view of a team's carried path: each platform's path (the QP motion solid, the
    baseline dashed) with its heading at ``poses`` instants, and the object (the segment through
    its farthest hands) at the same instants."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 7))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    runs = [(result.motion, "-", 1.0), (result.baseline, "--", 0.6)]
    for run, style, alpha in runs:
        picks = np.unique(np.linspace(0, len(run.t) - 1, poses).round().astype(int))
        for i, (member, q) in enumerate(zip(result.team.members, run.q)):
            color = colors[i % len(colors)]
            label = f"{member.name} ({'QP' if run.method == 'qp' else 'pseudo-inverse'})"
            ax.plot(q[:, 0], q[:, 1], style, color=color, alpha=alpha, label=label)
            if run.method == "qp":
                heading = np.arctan2(q[picks, 3], q[picks, 2])
                ax.quiver(
                    q[picks, 0], q[picks, 1], np.cos(heading), np.sin(heading), color=color, scale=20, width=0.004
                )
        if run.method == "qp":
            hands = result.hand_positions(run)[picks]
            for k, points in enumerate(hands):
                gaps = np.linalg.norm(points[:, None, :2] - points[None, :, :2], axis=2)
                a, b = np.unravel_index(int(np.argmax(gaps)), gaps.shape)
                ax.plot(points[[a, b], 0], points[[a, b], 1], color="0.2", lw=3, alpha=0.35 + 0.65 * k / len(hands),
                        label="object" if k == 0 else None)  # fmt: skip
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"team {result.team.name}: platforms and object, top view")
    fig.tight_layout()
    return fig
