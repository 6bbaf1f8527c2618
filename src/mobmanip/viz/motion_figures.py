"""Figures of motions over time: a trajectory's demands against its capacity
(``mobmanip trajectory --out``), the capacity profiles of a carried path (``mobmanip carry
--out``, ``mobmanip team-carry --out``), the top view of a team's carried path and the fastest
timing of a path with its limit curve (``mobmanip retime --out``).

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
    from ..motion.retime import Retiming
    from ..motion.trajectory_analysis import TrajectoryAnalysis


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # figures are written to files; no display needed
    import matplotlib.pyplot as plt

    return plt


def trajectory_figure(result: TrajectoryAnalysis) -> Figure:
    """Three panels over time: speed against velocity capacity, acceleration against
    acceleration capacity, and the largest velocity and effort use (fractions of the limits).

    Each axis carries the unit of the task's coordinates (``m/s`` for a planar task, ``mixed:
    m/s, rad/s`` where the task mixes linear and angular rows, whose norms mix them too); the
    legends stand right of the panels, outside the data."""
    from ..measures import ACCELERATION, VELOCITY
    from .labels import task_unit

    plt = _pyplot()
    t = result.trajectory.t
    task = result.task
    fig, axes = plt.subplots(3, 1, figsize=(9.5, 8.5), sharex=True, layout="constrained")
    ax = axes[0]
    ax.plot(t, np.linalg.norm(result.object_velocity, axis=1), label="object speed $|v_o|$")
    ax.plot(t, result.velocity_capacity, label="kinematic capacity along $v_o$")
    if result.velocity_polytope_capacity is not None:
        ax.plot(t, result.velocity_polytope_capacity, label="kinematic polytope along $v_o$")
    ax.plot(t, result.kinematic_semi_axes[:, -1], "--", label="kinematic minor semi-axis")
    ax.set_ylabel(f"velocity ({task_unit(VELOCITY, task)})")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax = axes[1]
    ax.plot(t, np.linalg.norm(result.object_acceleration, axis=1), label="object acceleration $|a_o|$")
    ax.plot(t, result.acceleration_capacity, label="dynamic capacity along $a_o$ (in motion)")
    ax.set_ylabel(f"acceleration ({task_unit(ACCELERATION, task)})")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax = axes[2]
    ax.plot(t, result.velocity_use.max(axis=1), label="largest $|x_i| / \\dot{x}_{\\max,i}$")
    ax.plot(t, result.effort_use.max(axis=1), label="largest $|\\tau_i| / \\tau_{\\max,i}$")
    ax.axhline(1.0, color="k", lw=0.8, label="limit")
    ax.set_ylabel("use of the limit (1)")
    ax.set_xlabel("$t$ (s)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    k = result.scaling.k_max
    margin = "unbounded" if k is None else (f"{k:.3f}" if result.scaling.feasible else "none")
    fig.suptitle(f"{result.robot_name}, {task} task: time-scaling margin {margin}")
    return fig


def carry_figure(result: CarryResult | TeamCarryResult, robot_name: str | None = None) -> Figure:
    """The objective over time along a carried path: the self-motion before the path (when there
    is one), the QP motion with its capacity term and the weighted pseudo-inverse baseline (and
    the baseline from the QP's prepared start, when it was run), of one robot or of a team
    (:func:`mobmanip.coordination.team_carry`). The y axis names the objective with its unit;
    the legend stands below the plot."""
    from .labels import objective_label, objective_words

    plt = _pyplot()
    motion, base = result.motion, result.baseline
    fig, ax = plt.subplots(figsize=(7.5, 4.2), layout="constrained")
    prep = result.preparation
    if prep is not None:
        ax.plot(prep.t, prep.capacity, color="0.5", label="self-motion before the path (object held still)")
    ax.plot(motion.t, motion.capacity, label="QP with capacity term")
    ax.plot(base.t, base.capacity, label="weighted pseudo-inverse from the start posture")
    prepared = getattr(result, "prepared_baseline", None)
    if prepared is not None:
        ax.plot(prepared.t, prepared.capacity, "--", label="weighted pseudo-inverse from the QP's prepared start")
    ax.set_xlabel("$t$ (s)")
    ax.set_ylabel(objective_label(result.objective, result.task))
    who = f"{robot_name}: " if robot_name else ""
    ax.set_title(f"{who}{objective_words(result.objective, result.task)} along the carried path", fontsize=10)
    ax.grid(True, lw=0.3)
    fig.legend(loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    return fig


def team_carry_figure(result: TeamCarryResult, poses: int = 7) -> Figure:
    """Top view of a team's carried path: each platform's path (the QP motion solid, the
    baseline dashed) with its heading at ``poses`` instants, and the object (the segment through
    its farthest hands) at the same instants."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 7.6), layout="constrained")
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
    ax.set_xlabel("$x$ (m)")
    ax.set_ylabel("$y$ (m)")
    ax.grid(True, lw=0.3)
    fig.legend(loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    ax.set_title(f"team {result.team.name}: platforms and object, top view", fontsize=10)
    return fig


#: Colours of the binding rows' kinds in the retiming figure.
KIND_COLOURS = {
    "velocity": "tab:blue",
    "effort": "tab:orange",
    "tip-over": "tab:red",
    "contact": "tab:purple",
    "traction": "tab:green",
}


def retime_figure(result: Retiming) -> Figure:
    """Two panels over the path parameter s (the input's time): the fastest speed s' with the
    largest each grid point allows (the limit curve) and the largest from which the end is still
    reached at rest, the binding row's kind marked under it; and the new time against s."""
    plt = _pyplot()
    s = result.s
    fig, axes = plt.subplots(2, 1, figsize=(9.5, 6.5), sharex=True, layout="constrained", height_ratios=(2, 1))
    ax = axes[0]
    top = float(np.max(result.controllable)) * 1.15 or 1.0
    ax.plot(s, np.minimum(result.limit, 10.0 * top), color="0.6", lw=1.0, label="limit curve (each point alone)")
    ax.plot(s, result.controllable, "--", color="0.3", lw=1.0, label="largest s' that still stops at the end")
    ax.plot(s, result.speed, color="k", lw=1.6, label="fastest timing")
    ax.axhline(1.0, color="0.5", lw=0.8, ls=":", label="the input's timing (s' = 1)")
    kinds = np.asarray(result.binding_kind)
    for kind, colour in KIND_COLOURS.items():
        where = kinds == kind
        if where.any():
            marks = np.full(int(where.sum()), -0.04 * top)
            ax.scatter(s[where], marks, marker="|", color=colour, s=40, label=f"binds: {kind}")
    ax.set_ylim(-0.08 * top, top)
    ax.set_ylabel("speed along the path, s' (1)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax = axes[1]
    ax.plot(s, result.t - result.t[0], color="k", label="fastest timing")
    ax.plot(s, s - s[0], color="0.5", ls=":", label="the input's timing")
    ax.set_xlabel("path parameter $s$: the input's time (s)")
    ax.set_ylabel("time (s)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    floor = "on the floor" if result.floor is not None else "joint limits only"
    fig.suptitle(
        f"{result.robot_name}, {result.task} task, {floor}: {float(s[-1] - s[0]):.3g} s -> {result.duration:.3g} s"
    )
    return fig
