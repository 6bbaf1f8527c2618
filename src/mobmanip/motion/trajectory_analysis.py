"""Analyse a whole-body trajectory: both measures per sample, demands against capacity, and
the exact time-scaling margin.

Per sample (:func:`analyze_trajectory`): the kinematic ellipsoid and the in-motion dynamic one
(:mod:`mobmanip.motion`), the object's velocity v_o and acceleration a_o that the motion asks
for, how far each set reaches along the demand's direction (the capacity there), the wheel and
joint efforts the motion needs (the paper's policy, RNEA terms in motion) and each velocity and
effort as a fraction of its limit.

Time-scaling margin. Running the same path k times faster multiplies every reduced velocity by
k and every acceleration term (xdot, Coriolis and centrifugal, Jdot v, Wdot^T v_o, w x I w) by
k^2, while gravity stays: ``tau(k) = k^2 tau_dyn + tau_static``. With s = k^2 each limit
``|s tau_dyn_i + tau_static_i| <= tau_max_i`` and ``s x_i^2 <= xdot_max_i^2`` is an interval of s,
so the feasible speed-ups form one interval [k_min, k_max] found exactly; k_max is the margin
(1.5: the motion could run 1.5 times faster; 0.8: it must slow down by 20 %).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError
from ..robot.model import Robot
from ..robot.tasks import get_task
from ..sets.capacity import kinematic_polytope
from ..support.progress import progress_bar
from ..terms.builder import terms_at
from ..terms.constraints.base import Constraint
from ..terms.grasp import HeldObject
from .in_motion import motion_terms
from .step_constraints import check_constraints, path_timing_rows
from .trajectory import Trajectory

#: A sample's object acceleration is *impulsive* when it differs from its neighbours' mean
#: (interpolated to its time) by more than this share of the largest object acceleration ...
IMPULSE_SHARE = 0.25
#: ... and by more than this (m/s^2, rad/s^2): a motion standing still is not impulsive.
IMPULSE_FLOOR = 1e-3


def acceleration_deviation(t: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Per sample, the norm of a_i minus its neighbours' values interpolated linearly to t_i,
    (N,) (0 at both ends). Small (O(h) times the jump of the jerk) for a C2 motion sampled every
    h; of the size of a itself where the accelerations are impulses at some samples.

    Args:
        t: time stamps (s), (N,); a: accelerations, (N, m).
    """
    t = np.asarray(t, dtype=float)
    a = np.asarray(a, dtype=float).reshape(len(t), -1)
    out = np.zeros(len(t))
    if len(t) < 3:
        return out
    w = ((t[1:-1] - t[:-2]) / (t[2:] - t[:-2]))[:, None]
    between = (1.0 - w) * a[:-2] + w * a[2:]
    out[1:-1] = np.linalg.norm(a[1:-1] - between, axis=1)
    return out


def impulsive_samples(t: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Indices of the samples whose acceleration is impulsive (:data:`IMPULSE_SHARE`,
    :data:`IMPULSE_FLOOR`), ascending."""
    a = np.asarray(a, dtype=float).reshape(len(t), -1)
    scale = float(np.linalg.norm(a, axis=1).max()) if len(a) else 0.0
    bound = max(IMPULSE_SHARE * scale, IMPULSE_FLOOR)
    return np.flatnonzero(acceleration_deviation(t, a) > bound)


@dataclass(frozen=True)
class TimeScaling:
    """The speed-ups k that keep every wheel and joint within its velocity and effort limits.

    Attributes:
        k_max: the largest speed-up (``None`` when no limit bounds it: a motion standing still).
        k_min: the smallest (0 unless slowing down breaks an effort limit, e.g. a motion that
            leans on centrifugal force).
        feasible: whether some speed-up keeps every limit (False when gravity alone breaks one).
        sample: the sample where k_max is decided, or -1.
        limit: ``"velocity NAME"`` or ``"effort NAME"``: the limit reached at k_max, or ``""``.
    """

    k_max: float | None
    k_min: float
    feasible: bool
    sample: int
    limit: str

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def time_scaling(
    x: np.ndarray,
    tau_dynamic: np.ndarray,
    tau_static: np.ndarray,
    velocity_limits: np.ndarray,
    effort_limits: np.ndarray,
    names: tuple[str, ...],
    extra: Sequence[tuple[int, np.ndarray, np.ndarray, tuple[str, ...]]] = (),
) -> TimeScaling:
    """The exact interval of speed-ups (module doc).

    Args:
        x: reduced velocities per sample, (N, nx).
        tau_dynamic: efforts that scale with k^2 (N, nx); tau_static: those that do not, (N, nx).
        velocity_limits, effort_limits: (nx,).
        names: reduced velocity names, (nx,).
        extra: further rows ``c s <= d`` over s = k^2 at a sample, as (sample, c, d, labels)
            (a constraint's rows, :func:`mobmanip.motion.step_constraints.path_timing_rows` with
            s'' = 0); the limit they decide is named ``"constraint LABEL"``.
    """
    s_hi = np.full(x.shape, np.inf)
    s_lo = np.zeros(x.shape)
    moving = x != 0.0
    s_hi[moving] = (np.broadcast_to(velocity_limits, x.shape)[moving] / np.abs(x[moving])) ** 2
    vel_hi = s_hi.copy()
    T, a, b = effort_limits[None, :], tau_dynamic, tau_static
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.where(a > 0, (T - b) / a, np.where(a < 0, (-T - b) / a, np.inf))
        down = np.where(a > 0, (-T - b) / a, np.where(a < 0, (T - b) / a, -np.inf))
    still_bad = (a == 0) & (np.abs(b) > T)
    up[still_bad] = -np.inf
    eff_hi = up
    s_hi = np.minimum(s_hi, eff_hi)
    s_lo = np.maximum(s_lo, down)
    hi, lo = float(s_hi.min()), float(s_lo.max())
    i, j = np.unravel_index(int(np.argmin(s_hi)), s_hi.shape)
    kind = "velocity" if vel_hi[i, j] <= eff_hi[i, j] else "effort"
    where, limit = int(i), f"{kind} {names[j]}"
    for sample, c, d, labels in extra:
        for c_k, d_k, label in zip(c, d, labels):
            bound = d_k / c_k if c_k != 0.0 else (math.inf if d_k >= 0.0 else -math.inf)
            if c_k > 0.0 or (c_k == 0.0 and d_k < 0.0):
                if bound < hi:
                    hi, where, limit = bound, int(sample), f"constraint {label}"
            else:
                lo = max(lo, bound)
    feasible = hi >= lo and hi >= 0.0
    if not feasible:
        return TimeScaling(0.0, 0.0, False, -1, "")
    if math.isinf(hi):
        return TimeScaling(None, math.sqrt(max(lo, 0.0)), True, -1, "")
    return TimeScaling(math.sqrt(hi), math.sqrt(max(lo, 0.0)), True, where, limit)


def _reach(center: np.ndarray, G: np.ndarray, d: np.ndarray, empty: bool) -> float:
    """How far from the origin the set {c + G u : |u| <= 1} reaches along the unit direction d
    (0 when the origin is outside, the set empty or the ray leaves at once)."""
    if empty:
        return 0.0
    # |G^+ (s d - c)| = 1 in the range of G: s^2 |e|^2 - 2 s e.f + |f|^2 - 1 = 0
    Gp = np.linalg.pinv(G)
    e, f = Gp @ d, Gp @ center
    aa, bb, cc = float(e @ e), float(e @ f), float(f @ f) - 1.0
    if aa <= 0.0:
        return 0.0
    disc = bb * bb - aa * cc
    if disc < 0.0:
        return 0.0
    return max(0.0, (bb + math.sqrt(disc)) / aa)


@dataclass(frozen=True)
class TrajectoryAnalysis:
    """Per-sample measures and demands along a trajectory.

    Attributes:
        robot_name, task: what was analysed.
        names: reduced velocity names, (nx,).
        trajectory: the trajectory analysed.
        kinematic_semi_axes: (N, m) descending (m/s, rad/s).
        dynamic_semi_axes: (N, m) (m/s^2, rad/s^2); dynamic_center: (N, m); dynamic_empty: (N,).
        object_velocity: v_o (N, m); object_acceleration: a_o (N, m).
        velocity_capacity: how far the kinematic ellipsoid reaches along v_o's direction (N,)
            (0 where v_o = 0: then along the first axis).
        acceleration_capacity: how far the in-motion dynamic ellipsoid reaches from the origin
            along a_o's direction (N,).
        efforts: the wheel and joint efforts the motion needs (N m, N), (N, nx).
        velocity_polytope_capacity: the kinematic polytope's ``radius_along`` v_o's direction d
            (N,) (m/s, rad/s): like ``velocity_capacity`` for the ellipsoid, the support function
            max d . v over the set (the largest component along d of a velocity the wheels and
            joints can give; the speed straight along d can be less), or ``None`` when not asked
            for. At least ``velocity_capacity``: the ellipsoid lies inside the polytope.
        velocity_use, effort_use: ``|x| / xdot_max`` and ``|tau| / tau_max`` per sample, (N, nx). The
            Euclidean norm of an effort_use row (the CSV's ``effort_norm``) is the dynamic
            ellipsoid's measure of the demand: 1 on its boundary when the motion's
            accelerations are the paper's policy (no null-space acceleration).
        scaling: the time-scaling margin.
        impulsive: the samples whose object acceleration is impulsive (:func:`impulsive_samples`):
            an input whose accelerations jump between samples, e.g. a path interpolated
            linearly; its efforts and the time-scaling margin there come from those jumps.
    """

    robot_name: str
    task: str
    names: tuple[str, ...]
    trajectory: Trajectory
    kinematic_semi_axes: np.ndarray
    dynamic_semi_axes: np.ndarray
    dynamic_center: np.ndarray
    dynamic_empty: np.ndarray
    object_velocity: np.ndarray
    object_acceleration: np.ndarray
    velocity_capacity: np.ndarray
    acceleration_capacity: np.ndarray
    efforts: np.ndarray
    efforts_static: np.ndarray = field(repr=False)
    velocity_use: np.ndarray = field(repr=False)
    effort_use: np.ndarray = field(repr=False)
    scaling: TimeScaling = field(repr=False)
    velocity_polytope_capacity: np.ndarray | None = None
    impulsive: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))

    def table(self) -> tuple[list[str], np.ndarray]:
        """Per-sample CSV columns: header and values."""
        m = self.kinematic_semi_axes.shape[1]
        labels = get_task(self.task).labels
        header = ["t"]
        header += [f"v_o_{a}" for a in labels] + [f"a_o_{a}" for a in labels]
        header += ["speed", "velocity_capacity", "acceleration", "acceleration_capacity"]
        header += [f"kinematic_semi_axis_{k + 1}" for k in range(m)] + [f"dynamic_semi_axis_{k + 1}" for k in range(m)]
        header += ["dynamic_empty", "max_velocity_use", "max_effort_use", "effort_norm", "slip"]
        header += [f"effort_{n}" for n in self.names]
        polytope = [] if self.velocity_polytope_capacity is None else [self.velocity_polytope_capacity[:, None]]
        if polytope:
            header.append("velocity_polytope_capacity")
        cols = [
            self.trajectory.t[:, None],
            self.object_velocity,
            self.object_acceleration,
            np.linalg.norm(self.object_velocity, axis=1)[:, None],
            self.velocity_capacity[:, None],
            np.linalg.norm(self.object_acceleration, axis=1)[:, None],
            self.acceleration_capacity[:, None],
            self.kinematic_semi_axes,
            self.dynamic_semi_axes,
            self.dynamic_empty[:, None].astype(float),
            self.velocity_use.max(axis=1)[:, None],
            self.effort_use.max(axis=1)[:, None],
            np.linalg.norm(self.effort_use, axis=1)[:, None],
            self.trajectory.slip[:, None],
            self.efforts,
            *polytope,
        ]
        return header, np.hstack(cols)

    def to_dict(self) -> dict:
        """A JSON-ready summary and the per-sample columns."""
        header, values = self.table()
        extra = {}
        if self.velocity_polytope_capacity is not None:
            extra["min_velocity_polytope_capacity"] = float(self.velocity_polytope_capacity.min())
        return {
            "robot": self.robot_name,
            "task": self.task,
            "samples": len(self.trajectory),
            "duration": float(self.trajectory.t[-1] - self.trajectory.t[0]),
            "reduced_velocity_names": list(self.names),
            "time_scaling": self.scaling.to_dict(),
            "max_velocity_use": float(self.velocity_use.max()),
            "max_effort_use": float(self.effort_use.max()),
            "max_slip": float(self.trajectory.slip.max()),
            "min_velocity_capacity": float(self.velocity_capacity.min()),
            "min_acceleration_capacity": float(self.acceleration_capacity.min()),
            "impulsive_samples": [int(i) for i in self.impulsive],
            **extra,
            "columns": {name: values[:, k].tolist() for k, name in enumerate(header)},
        }


def analyze_trajectory(
    robot: Robot,
    trajectory: Trajectory,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
    polytope: bool = False,
    progress: bool = False,
    constraints: Sequence[Constraint] = (),
) -> TrajectoryAnalysis:
    """Both measures, the demands and the time-scaling margin along a trajectory.

    Args:
        robot: the loaded robot.
        trajectory: from :func:`mobmanip.motion.trajectory.read_trajectory` or
            :func:`mobmanip.motion.trajectory.trajectory_from_samples`.
        task, object_mass, held_object, decoupled: as :func:`mobmanip.analysis.analyze` (the
            default object sits between the hands at every sample).
        polytope: also the kinematic polytope's reach along v_o
            (:attr:`TrajectoryAnalysis.velocity_polytope_capacity`; one LP-backed support query per
            sample).
        progress: show a progress bar over the samples on standard error.
        constraints: constraints of the sets at rest the time-scaling margin also keeps: at each
            sample their rows over the motion run k times faster (velocities k x, accelerations
            k^2 xdot, efforts k^2 tau_dyn + tau_static;
            :func:`mobmanip.motion.step_constraints.path_timing_rows`); a constraint that cannot
            join a step of motion is refused by name.
    """
    if not isinstance(trajectory, Trajectory):
        raise ArgumentError(f"expected a Trajectory, got {type(trajectory).__name__}")
    constraints = check_constraints(constraints)
    task = get_task(task or robot.spec.default_task)
    n, m, nx = len(trajectory), task.dim, robot.nx
    kin_axes, dyn_axes, dyn_center = np.zeros((n, m)), np.zeros((n, m)), np.zeros((n, m))
    dyn_empty = np.zeros(n, dtype=bool)
    v_o, a_o = np.zeros((n, m)), np.zeros((n, m))
    v_cap, a_cap = np.zeros(n), np.zeros(n)
    tau, tau_static = np.zeros((n, nx)), np.zeros((n, nx))
    v_poly = np.zeros(n) if polytope else None
    with progress_bar(n, desc=f"trajectory {robot.name}", unit="sample", show=progress) as bar:
        for i in range(n):
            bar.update(1)
            terms = motion_terms(
                robot,
                trajectory.q[i],
                trajectory.x[i],
                task,
                object_mass=object_mass,
                held_object=held_object,
                decoupled=decoupled,
            )
            kin, dyn = terms.kinematic(), terms.dynamic()
            kin_axes[i], dyn_axes[i], dyn_center[i], dyn_empty[i] = kin.semi_axes, dyn.semi_axes, dyn.center, dyn.empty
            xdot = trajectory.xdot[i]
            v_o[i] = terms.v_o
            a_o[i] = terms.object_acceleration(xdot)
            tau[i] = terms.torques(xdot, a_o[i])
            tau_static[i] = terms.static_torques()
            speed = float(np.linalg.norm(v_o[i]))
            d = v_o[i] / speed if speed > 0.0 else kin.axes[0]
            v_cap[i] = kin.radius_along(d) if not kin.empty else 0.0
            if v_poly is not None:
                v_poly[i] = kinematic_polytope(terms.J_u, terms.W, terms.velocity_limits).radius_along(d)
            acc = float(np.linalg.norm(a_o[i]))
            d = a_o[i] / acc if acc > 0.0 else dyn.axes[0]
            a_cap[i] = _reach(dyn.center, dyn.generator, d, dyn.empty)
    vlim = np.asarray(robot.velocity_limits, dtype=float)
    elim = np.asarray(robot.effort_limits, dtype=float)
    names = robot.reduced_velocity_names
    extra = []
    for i in range(n) if constraints else ():  # run k times faster: s' = k, s'' = 0, b = k^2
        at_rest = terms_at(robot, trajectory.q[i], task.name, object_mass=object_mass, check=False)
        _, c, d, labels = path_timing_rows(constraints, at_rest, trajectory.x[i], trajectory.xdot[i],
                                           (np.zeros(nx), tau[i] - tau_static[i], tau_static[i]))  # fmt: skip
        extra.append((i, c, d, labels))
    scaling = time_scaling(trajectory.x, tau - tau_static, tau_static, vlim, elim, names, extra)
    return TrajectoryAnalysis(
        robot_name=robot.name,
        task=task.name,
        names=names,
        trajectory=trajectory,
        kinematic_semi_axes=kin_axes,
        dynamic_semi_axes=dyn_axes,
        dynamic_center=dyn_center,
        dynamic_empty=dyn_empty,
        object_velocity=v_o,
        object_acceleration=a_o,
        velocity_capacity=v_cap,
        acceleration_capacity=a_cap,
        efforts=tau,
        efforts_static=tau_static,
        velocity_use=np.abs(trajectory.x) / vlim,
        effort_use=np.abs(tau) / elim,
        scaling=scaling,
        velocity_polytope_capacity=v_poly,
        impulsive=impulsive_samples(trajectory.t, a_o),
    )
