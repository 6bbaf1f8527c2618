"""Figures of motions over time: a trajectory's demands against its capacity
(``mobmanip trajectory --out``) and the capacity profiles of a carried path (``mobmanip carry
--out``).

Each function returns a matplotlib ``Figure``; the caller saves it
(:func:`mobmanip.support.files.save_figure`) and closes it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..motion.carry import CarryResult
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


def carry_figure(result: CarryResult, robot_name: str | None = None) -> Figure:
    """The objective over time along a carried path: the self-motion before the path (when there
    is one), the QP motion with its capacity term and the weighted pseudo-inverse baseline (and
    the baseline from the QP's prepared start, when it was run). The y axis names the objective
    with its unit; the legend stands below the plot."""
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
