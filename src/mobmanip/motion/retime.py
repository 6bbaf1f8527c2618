"""The fastest timing of a path: time-optimal path parameterisation by reachability analysis.

A whole-body path is the configurations of a trajectory, q(s), with s its original time
stamps. Running it with a new timing s(t) gives reduced velocities and accelerations

    x = x_s s',    xdot = x_s s'' + x_ss s'^2,

where x_s and x_ss are the trajectory's own reduced velocities and accelerations (the timing
s' = 1 gives the trajectory back). Every velocity term of the dynamics (Coriolis, centrifugal,
the hands' drift, the moving grasp) is quadratic in x, so with a = s'' and b = s'^2, at each
grid point s_i:

- a wheel or joint velocity limit is ``x_s,j^2 b <= xdot_max,j^2``;
- an effort is ``tau = T_a a + T_b b + T_0`` (the paper's policy with the held object, as
  :meth:`mobmanip.motion.in_motion.MotionTerms.torques`), kept in ``|tau_j| <= tau_max,j``;
- the floor's resultant wrench on the robot and its object is affine in (a, b) the same way
  (:func:`mobmanip.motion.ground.floor_wrench`), and the floor's rows are linear in that wrench
  (:func:`mobmanip.motion.carry_floor.wrench_rows`: the zero-moment point a margin inside the
  support polygon, every support loaded, each driven wheel within friction, with a reserve).

Each grid point therefore gives a convex polygon of (a, b). With b_{i+1} = b_i + 2 (s_{i+1} -
s_i) a_i (a constant on each interval, kept by the rows at both of the interval's ends: TOPP-RA's
"interpolation" scheme, :data:`DISCRETIZATIONS`), reachability analysis (TOPP-RA: Pham and Pham, IEEE
T-RO 2018) gives the time-optimal profile exactly on the grid: a backward pass computes each
point's controllable set K_i, the values of b from which the end can still be reached at rest,
and a forward pass from rest takes at each point the largest a that keeps the next b in
K_{i+1}. The polygons are two-dimensional, so each of those linear programs is solved exactly
by clipping the polygon (no LP solver, no tolerance of one).

The new time stamps follow from ``t_{i+1} - t_i = 2 (s_{i+1} - s_i) / (s'_i + s'_{i+1})``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from ..errors import ArgumentError, NumericalError, SpecError
from ..robot.model import Robot
from ..robot.tasks import get_task
from ..terms.builder import terms_at
from ..terms.grasp import object_mass_of
from .carry_floor import NO_TURN, CarryFloor, turning_row
from .path_terms import path_terms
from .step_constraints import check_constraints, path_timing_rows
from .trajectory import Trajectory

#: The largest speed-up of the path parameter the solver looks at, s' <= this (the original
#: timing is s' = 1): a path nothing limits runs into it and is refused.
SPEED_CAP = 1e3
#: The largest s'' (either sign) it looks at, in units of the input's timing.
ACCELERATION_CAP = 1e8
#: A polygon's vertex keeps a row when it breaks it by less than this, relative to the row's scale.
ROW_TOLERANCE = 1e-12


@dataclass(frozen=True)
class PathRows:
    """The rows of one grid point over (a, b) = (s'', s'^2): ``ca a + cb b <= d``.

    Attributes:
        ca, cb, d: (r,) each.
        labels: what each row keeps (``"velocity NAME"``, ``"effort NAME"`` or the floor's), (r,).
        kinds: each row's kind: ``"velocity"``, ``"effort"``, ``"tip-over"``, ``"contact"``,
            ``"traction"`` or ``"constraint"`` (a constraint given to :func:`path_rows`), (r,).
    """

    ca: np.ndarray
    cb: np.ndarray
    d: np.ndarray
    labels: tuple[str, ...]
    kinds: tuple[str, ...]


def path_rows(
    robot: Robot,
    trajectory: Trajectory,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    floor: CarryFloor | None = None,
    progress: bool = False,
    constraints: tuple = (),
) -> list[PathRows]:
    """Every grid point's rows over (s'', s'^2) (see the module's docstring).

    Args:
        robot: the loaded robot.
        trajectory: the path, its time stamps the path parameter s.
        task, object_mass: the task space and the object held between the hands (default: the
            spec's), as :func:`mobmanip.motion.trajectory_analysis.analyze_trajectory`.
        floor: also keep the robot on its floor (as ``carry``'s floor, every platform on wheels);
            on a ramp (``floor.slope``) the efforts and the floor's wrench take its leaning gravity.
        progress: a progress bar over the grid points on standard error.
        constraints: constraints of the sets at rest kept at every grid point, their rows over the
            reduced velocities or efforts written over (s'', s'^2)
            (:func:`mobmanip.motion.step_constraints.path_timing_rows`; kind ``"constraint"``).

    Raises:
        ArgumentError: a constraint that cannot join a step of motion (named).
    """
    constraints = check_constraints(constraints)
    task_space = get_task(task or robot.spec.default_task)
    mass = object_mass_of(robot, object_mass)
    floor_rows = None if floor is None else floor.rows(robot, mass)
    if floor_rows is not None:
        _check_no_turn(robot, trajectory)
    gravity = None if floor is None or not floor.slope else floor.gravity()  # a ramp: the weights lean
    terms = path_terms(robot, trajectory, task_space, mass, wrench=floor_rows is not None, progress=progress,
                       gravity=gravity)  # fmt: skip
    vlim = np.asarray(robot.velocity_limits, dtype=float)
    elim = np.asarray(robot.effort_limits, dtype=float)
    names = robot.reduced_velocity_names
    nx = robot.nx
    efforts = [f"effort {n}" for n in names] * 2
    out = []
    for i in range(len(trajectory)):
        x_s = trajectory.x[i]
        T_a, T_b, static = terms.effort_a[i], terms.effort_b[i], terms.effort_0[i]
        moves = np.flatnonzero(x_s != 0.0)
        ca = [np.zeros(len(moves)), T_a, -T_a]
        cb = [x_s[moves] ** 2, T_b, -T_b]
        d = [vlim[moves] ** 2, elim - static, elim + static]
        labels = [f"velocity {names[j]}" for j in moves] + efforts
        kinds = ["velocity"] * len(moves) + ["effort"] * (2 * nx)
        if floor_rows is not None:
            R, r = floor_rows.at(trajectory.q[i])
            resting = terms.wrench_0[i]  # type: ignore[index]
            ca.append(R @ terms.wrench_a[i])  # type: ignore[index]
            cb.append(R @ terms.wrench_b[i])  # type: ignore[index]
            d.append(r - R @ resting)
            labels += floor_rows.labels
            kinds += floor_rows.kinds
        if constraints:
            at_rest = terms_at(robot, trajectory.q[i], task_space.name, object_mass=mass, check=False)
            more = path_timing_rows(constraints, at_rest, x_s, trajectory.xdot[i], (T_a, T_b, static))
            ca.append(more[0])
            cb.append(more[1])
            d.append(more[2])
            labels += more[3]
            kinds += ["constraint"] * len(more[3])
        out.append(PathRows(np.concatenate(ca), np.concatenate(cb), np.concatenate(d), tuple(labels), tuple(kinds)))
    return out


def _check_no_turn(robot: Robot, trajectory: Trajectory) -> None:
    """A skid-steer's path on the floor drives straight (see :data:`~mobmanip.motion.carry_floor.NO_TURN`).

    Raises:
        SpecError: the path turns the base, at its first such sample.
    """
    if turning_row(robot, trajectory.q[0]) is None:
        return
    rates = np.array([turning_row(robot, q) @ x for q, x in zip(trajectory.q, trajectory.x)])
    speeds = np.abs(trajectory.x).max(axis=1)
    turns = np.abs(rates) > 1e-6 * np.maximum(speeds, 1e-300)  # a file's rounding is no turn
    if np.any(turns):
        i = int(np.argmax(np.where(turns, np.abs(rates), -1.0)))
        raise SpecError(
            f"the path turns {robot.name}'s base ({rates[i]:.4g} rad/s at sample {i}, t = {trajectory.t[i]:.6g} s, "
            f"the fastest turn): {NO_TURN}; retime it without --ground, or give a path that drives straight"
        )


#: How each interval's constant s'' keeps the rows: ``"interpolation"`` at both of its ends (the
#: sample's rows at (s'', s'^2) and the next sample's at (s'', s'^2 + 2 ds s'')), ``"collocation"``
#: at its start only (the next sample then checks its own rows with the next interval's s'').
DISCRETIZATIONS = ("interpolation", "collocation")


def interval_rows(rows: list[PathRows], s: np.ndarray, discretization: str = "interpolation") -> list[PathRows]:
    """The rows each interval's (s'', s'^2 at its start) keeps, one per sample (the last sample:
    its own rows, with s' = 0 there): see :data:`DISCRETIZATIONS`.

    Raises:
        ArgumentError: an unknown discretization.
    """
    if discretization not in DISCRETIZATIONS:
        raise ArgumentError(f"discretization must be one of {', '.join(DISCRETIZATIONS)}, got {discretization!r}")
    if discretization == "collocation":
        return list(rows)
    kept = []
    for i in range(len(rows) - 1):
        here, there, step = rows[i], rows[i + 1], float(s[i + 1] - s[i])
        kept.append(
            PathRows(
                np.concatenate([here.ca, there.ca + 2.0 * step * there.cb]),
                np.concatenate([here.cb, there.cb]),
                np.concatenate([here.d, there.d]),
                here.labels + there.labels,
                here.kinds + there.kinds,
            )
        )
    return [*kept, rows[-1]]


# ----- exact two-dimensional programs -----


#: A polygon: its vertices in order, each with the line (ca, cb, d), normalised, of the edge
#: that leaves it (``ca a + cb b = d``).
Polygon = list[tuple[float, float, tuple[float, float, float]]]


def _meet(first: tuple[float, float, float], second: tuple[float, float, float]) -> tuple[float, float]:
    """Where two lines cross (Cramer's rule: exact to rounding however far the vertices are)."""
    det = first[0] * second[1] - first[1] * second[0]
    return (
        (first[2] * second[1] - first[1] * second[2]) / det,
        (first[0] * second[2] - first[2] * second[0]) / det,
    )


def _clip(polygon: Polygon, ca: float, cb: float, d: float) -> Polygon:
    """A convex polygon cut by the half-plane ``ca a + cb b <= d``. A new vertex is computed as
    the crossing of the cut with the edge's own line, not along the edge from its ends, so that
    vertices far away (the solver's caps) cost no precision."""
    scale = math.hypot(ca, cb)
    if scale == 0.0:
        return polygon if d >= -ROW_TOLERANCE * max(1.0, abs(d)) else []
    cut = (ca / scale, cb / scale, d / scale)
    tol = ROW_TOLERANCE * (1.0 + abs(cut[2]))
    values = [cut[0] * a + cut[1] * b - cut[2] for a, b, _ in polygon]
    inside = [v <= tol for v in values]
    if all(inside):
        return polygon
    out: Polygon = []
    n = len(polygon)
    for k in range(n):
        a, b, edge = polygon[k]
        if inside[k]:
            out.append((a, b, edge))
        if n > 1 and inside[k] != inside[(k + 1) % n]:
            if abs(edge[0] * cut[1] - edge[1] * cut[0]) > 1e-12:
                crossing = _meet(edge, cut)
            else:  # an edge along the cut, its ends either side of it by rounding: where it is cut
                nxt, w = polygon[(k + 1) % n], values[k] / (values[k] - values[(k + 1) % n])
                crossing = (a + w * (nxt[0] - a), b + w * (nxt[1] - b))
            # leaving the half-plane: the cut is the next edge; entering it: this edge goes on
            out.append((*crossing, cut if inside[k] else edge))
    return out


def _polygon(rows: PathRows) -> Polygon:
    """The grid point's feasible (a, b), within the solver's caps. Each cut keeps a polygon
    inside the last, so a row every vertex keeps stays kept: only the most broken row is cut by,
    until none is (a few cuts, however many rows)."""
    top, cap = SPEED_CAP**2, ACCELERATION_CAP
    polygon: Polygon = [
        (-cap, 0.0, (0.0, -1.0, 0.0)),  # along b = 0
        (cap, 0.0, (1.0, 0.0, cap)),  # up a = cap
        (cap, top, (0.0, 1.0, top)),  # along b = top
        (-cap, top, (-1.0, 0.0, cap)),  # down a = -cap
    ]
    scale = np.hypot(rows.ca, rows.cb)
    if np.any(rows.d[scale == 0.0] < -ROW_TOLERANCE * np.maximum(1.0, np.abs(rows.d[scale == 0.0]))):
        return []
    moving = scale > 0.0
    ca, cb, d = (v[moving] / scale[moving] for v in (rows.ca, rows.cb, rows.d))
    d_tol = d + ROW_TOLERANCE * (1.0 + np.abs(d))
    if not len(d):  # nothing moves at this grid point (a path standing still): no row cuts
        return polygon
    for _ in range(len(d) + 1):
        a, b = np.array([vertex[0] for vertex in polygon]), np.array([vertex[1] for vertex in polygon])
        broken = (ca[:, None] * a + cb[:, None] * b).max(axis=1) - d_tol
        k = int(np.argmax(broken))
        if broken[k] <= 0.0:
            return polygon
        polygon = _clip(polygon, float(ca[k]), float(cb[k]), float(d[k]))
        if not polygon:
            return []
        # a row this polygon keeps, every later (smaller) one keeps: only the broken ones are left
        still = broken > 0.0
        still[k] = False
        ca, cb, d, d_tol = ca[still], cb[still], d[still], d_tol[still]
        if not len(d):
            return polygon
    return polygon


def _strip(polygon: Polygon, step: float, lo: float, hi: float) -> Polygon:
    """The part of the polygon whose next b, ``b + 2 step a``, lies in [lo, hi]."""
    out = _clip(polygon, 2.0 * step, 1.0, hi)
    return _clip(out, -2.0 * step, -1.0, -lo) if out else []


def _reaches(polygon, *, step: float, lo: float, hi: float) -> bool:
    """Whether some (a, b) of the polygon has its next b in [lo, hi]."""
    return bool(_strip(polygon, step, lo, hi))


def _b_range(polygon) -> tuple[float, float] | None:
    if not polygon:
        return None
    bs = [b for _, b, _ in polygon]
    return max(min(bs), 0.0), max(bs)


def _a_range(polygon: Polygon, b: float) -> tuple[float, float]:
    """The s'' the polygon allows at s'^2 = b: its cut along that line (a b a hair above the
    polygon's top, by rounding: the top vertex's)."""
    cut = _clip(_clip(polygon, 0.0, 1.0, b), 0.0, -1.0, -b)
    if not cut:
        top = max(polygon, key=lambda vertex: vertex[1])
        return top[0], top[0]
    values = [a for a, _, _ in cut]
    return min(values), max(values)


@dataclass(frozen=True)
class Retiming:
    """The time-optimal timing of a path.

    Attributes:
        robot_name, task: what was retimed.
        s: the path parameter at the grid points, the input's time stamps (s), (N,).
        t: the new time stamps, starting where the input starts (s), (N,).
        speed: s' at each grid point (1: the input's own speed there), (N,).
        acceleration: s'' on each interval, repeated at the last point, (N,).
        limit: the largest s' each grid point allows alone (the maximum velocity curve), (N,).
        controllable: the largest s' from which the end is still reached at rest, (N,).
        binding: per grid point, the row nearest to binding at the chosen (s'', s'^2), (N,).
        binding_kind: its kind, (N,).
        trajectory: the retimed motion (its x and xdot exact on the grid).
        floor: the floor kept (its description), or ``None``.
        notes: what the user should know of the result: an end of the path where the robot is at
            rest only while it accelerates (it cannot stand still there within the rows).
        stops: braking along the path (:func:`stops_along`), when asked for.
        constraints: the constraints kept beside the limits and the floor (their descriptions).
    """

    robot_name: str
    task: str
    s: np.ndarray
    t: np.ndarray
    speed: np.ndarray
    acceleration: np.ndarray
    limit: np.ndarray
    controllable: np.ndarray
    binding: tuple[str, ...]
    binding_kind: tuple[str, ...]
    trajectory: Trajectory = field(repr=False)
    floor: dict | None = None
    notes: tuple[str, ...] = ()
    stops: Stops | None = None
    constraints: tuple[dict, ...] = ()

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def binding_runs(self) -> list[tuple[float, float, str]]:
        """The path cut where the binding row changes: (from s, to s, label) per run."""
        runs: list[tuple[float, float, str]] = []
        start = 0
        for i in range(1, len(self.binding) + 1):
            if i == len(self.binding) or self.binding[i] != self.binding[start]:
                runs.append((float(self.s[start]), float(self.s[i - 1]), self.binding[start]))
                start = i
        return runs

    def table(self) -> tuple[list[str], np.ndarray]:
        """Per grid point: s, t, s', s'', the limit curve and the controllable bound."""
        header = ["s", "t", "speed", "acceleration", "limit", "controllable"]
        values = np.c_[self.s, self.t, self.speed, self.acceleration, self.limit, self.controllable]
        return header, values

    def to_dict(self) -> dict:
        header, values = self.table()
        return {
            "robot": self.robot_name,
            "task": self.task,
            "samples": len(self.s),
            "input_duration": float(self.s[-1] - self.s[0]),
            "duration": self.duration,
            "floor": self.floor,
            "constraints": [dict(c) for c in self.constraints],
            "notes": list(self.notes),
            "stops": None if self.stops is None else self.stops.to_dict(),
            "binding": [{"from_s": a, "to_s": b, "row": label} for a, b, label in self.binding_runs()],
            "columns": {name: values[:, k].tolist() for k, name in enumerate(header)}
            | {"binding": list(self.binding), "binding_kind": list(self.binding_kind)},
        }


def retime(
    robot: Robot,
    trajectory: Trajectory,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    floor: CarryFloor | None = None,
    progress: bool = False,
    rows: list[PathRows] | None = None,
    discretization: str = "interpolation",
    constraints: tuple = (),
) -> Retiming:
    """The fastest timing of ``trajectory``'s path, from rest to rest, with every wheel and joint
    within its velocity and effort limits and, with ``floor``, the robot on its floor (see the
    module's docstring).

    Args:
        robot, trajectory, task, object_mass, floor, progress, constraints: as :func:`path_rows`.
        rows: the path's rows when already computed (:func:`path_rows`), else computed here.
        discretization: how each interval keeps the rows (:data:`DISCRETIZATIONS`): at both of its
            ends (default; TOPP-RA's "interpolation") or at its start ("collocation").

    Raises:
        ArgumentError: not a trajectory, an unknown discretization.
        NumericalError: no timing keeps the rows (named: the grid point and, where one row alone
            decides, the row), or nothing limits the speed.
    """
    if not isinstance(trajectory, Trajectory):
        raise ArgumentError(f"expected a Trajectory, got {type(trajectory).__name__}")
    if rows is None:
        rows = path_rows(robot, trajectory, task, object_mass=object_mass, floor=floor, progress=progress,
                         constraints=constraints)  # fmt: skip
    s = trajectory.t
    n = len(s)
    steps = np.diff(s)
    own = rows
    rows = interval_rows(own, s, discretization)
    unsteady = {}  # an end where the robot is at rest only while it accelerates
    for i, where in ((0, "first"), (n - 1, "last")):
        still = _still_breaks(own[i])
        if still:
            unsteady[where] = f"the {where} sample cannot be held still (s'' = 0): {still}"
    context = "".join(f"; {note}" for note in unsteady.values())
    polygons = [_polygon(r) for r in rows]
    for i, polygon in enumerate(polygons):
        if not polygon:
            raise NumericalError(
                f"no timing of the path keeps {_blocking(rows[i])} at sample {i} (s = {s[i]:.6g} s){context}"
            )
    limit = np.array([math.sqrt(_b_range(p)[1]) for p in polygons])  # type: ignore[index]

    # backward: the controllable sets, ending at rest
    K = np.zeros((n, 2))
    for i, where in ((0, "first"), (n - 1, "last")):  # from rest to rest: s' = 0 at both ends
        if not _clip(polygons[i], 0.0, 1.0, 0.0):
            at_rest = _blocking(rows[i], lambda polygon: bool(_clip(polygon, 0.0, 1.0, 0.0)))
            raise NumericalError(f"the path's {where} sample cannot be passed at rest: {at_rest}{context}")
    for i in range(n - 2, -1, -1):
        step, lo, hi = float(steps[i]), K[i + 1, 0], K[i + 1, 1]
        found = _b_range(_strip(polygons[i], step, lo, hi))
        if found is None:
            blocking = _blocking(rows[i], partial(_reaches, step=step, lo=lo, hi=hi))
            raise NumericalError(
                f"no timing of the path reaches its end at rest from sample {i} (s = {s[i]:.6g} s): "
                f"{blocking} there{context}"
            )
        K[i] = found
    if K[0, 0] > 0.0:
        raise NumericalError(f"the path cannot start from rest: {_blocking(rows[0])}")

    # forward: the greatest acceleration that stays controllable
    b = np.zeros(n)
    a = np.zeros(n)
    for i in range(n - 1):
        lo, hi = _a_range(polygons[i], b[i])
        step = float(steps[i])
        hi = min(hi, (K[i + 1, 1] - b[i]) / (2.0 * step))
        lo = max(lo, (K[i + 1, 0] - b[i]) / (2.0 * step))
        a[i] = hi if hi >= lo else lo  # equal up to rounding where the set is one point
        b[i + 1] = min(max(b[i] + 2.0 * step * a[i], K[i + 1, 0]), K[i + 1, 1])
        a[i] = (b[i + 1] - b[i]) / (2.0 * step)
    a[-1] = a[-2]
    if np.any(b >= (1.0 - 1e-9) * SPEED_CAP**2):
        raise NumericalError(
            f"nothing limits the path's speed (s' reached the solver's cap {SPEED_CAP:g} times the input's): "
            "give the robot velocity or effort limits"
        )
    speed = np.sqrt(b)
    dt = np.zeros(n - 1)
    both = speed[:-1] + speed[1:]
    dt[both > 0.0] = 2.0 * steps[both > 0.0] / both[both > 0.0]
    t = s[0] + np.r_[0.0, np.cumsum(dt)]
    if np.any(np.diff(t) <= 0.0):
        k = int(np.flatnonzero(np.diff(t) <= 0.0)[0])
        raise NumericalError(
            f"the retimed path passes samples {k} and {k + 1} in no time (a part of the path where nothing moves); "
            "remove the repeated samples"
        )
    x = trajectory.x * speed[:, None]
    xdot = trajectory.x * a[:, None] + trajectory.xdot * b[:, None]
    retimed = Trajectory(t, trajectory.q, x, xdot, trajectory.slip * speed)
    binding, kinds = zip(*(_binding(r, a[i], b[i]) for i, r in enumerate(rows)))
    return Retiming(
        robot_name=robot.name,
        task=get_task(task or robot.spec.default_task).name,
        s=s.copy(),
        t=t,
        speed=speed,
        acceleration=a,
        limit=limit,
        controllable=np.sqrt(K[:, 1]),
        binding=tuple(binding),
        binding_kind=tuple(kinds),
        trajectory=retimed,
        floor=None if floor is None else floor.describe(),
        notes=tuple(unsteady.values()),
        constraints=tuple(c.describe() for c in check_constraints(constraints)),
    )


def _stop_bound(polygons, steps: np.ndarray, start: int, end: int) -> float:
    """The largest s'^2 at ``start`` from which the robot stops at ``end`` (its controllable set's
    top, the backward pass from rest at ``end``), or -1 when none does (it cannot rest at ``end``, or
    some sample between leaves no timing)."""
    if not _clip(polygons[end], 0.0, 1.0, 0.0):
        return -1.0
    lo, hi = 0.0, 0.0
    for i in range(end - 1, start - 1, -1):
        found = _b_range(_strip(polygons[i], float(steps[i]), lo, hi))
        if found is None:
            return -1.0
        lo, hi = found
    return hi


def _base_distance(robot: Robot, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """The platform's travelled distance from the first sample (m), (N,), and its speed per unit
    of the path parameter, |d(x, y)/ds| (m/s at s' = 1), (N,)."""
    steps = np.linalg.norm(np.diff(trajectory.q[:, :2], axis=0), axis=1)
    rates = np.array([np.linalg.norm((robot.null_space(q) @ x)[:2]) for q, x in zip(trajectory.q, trajectory.x)])
    return np.r_[0.0, np.cumsum(steps)], rates


#: Where the path drives its platform, for the lowest speed that stops (:meth:`Stops.slowest`): at
#: least this share of the platform's fastest rate along the path.
DRIVING = 0.1


@dataclass(frozen=True)
class Stops:
    """Braking along a path, on the rows :func:`path_rows` gives (see :func:`stops_along`).

    Attributes:
        s: the path parameter at the samples, (N,).
        distance: the platform's travelled distance from the first sample (m), (N,).
        within: the distance a stop must take at most (m).
        speed: at each sample, the largest s' from which the robot stops within ``within`` metres
            of the platform's travel (0 where it cannot: a sample it cannot pass at rest), (N,).
        base_speed: the same as the platform's speed (m/s), (N,).
        stop_at: the sample where each stop ends: the last within the distance, (N,).
        platform_rate: the platform's speed per unit of s (m/s at s' = 1), (N,).
    """

    s: np.ndarray
    distance: np.ndarray
    within: float
    speed: np.ndarray
    base_speed: np.ndarray
    stop_at: np.ndarray
    platform_rate: np.ndarray

    def slowest(self) -> int:
        """The sample with the lowest such platform speed among those with the whole distance
        ahead of them where the path drives the platform (at least :data:`DRIVING` of its fastest
        rate: elsewhere the path's end, or the arms moving while the platform creeps, decides), or
        -1 when there is none."""
        ahead = self.distance[-1] - self.distance >= self.within
        candidates = np.flatnonzero(ahead & (self.platform_rate >= DRIVING * self.platform_rate.max()))
        return int(candidates[np.argmin(self.base_speed[candidates])]) if candidates.size else -1

    def to_dict(self) -> dict:
        k = self.slowest()
        return {
            "within": self.within,
            "lowest_base_speed": None if k < 0 else float(self.base_speed[k]),
            "lowest_at_sample": None if k < 0 else k,
            "columns": {
                "s": self.s.tolist(),
                "distance": self.distance.tolist(),
                "speed": self.speed.tolist(),
                "base_speed": self.base_speed.tolist(),
                "stop_at": self.stop_at.tolist(),
            },
        }


def stops_along(
    robot: Robot,
    trajectory: Trajectory,
    within: float,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    floor: CarryFloor | None = None,
    rows: list[PathRows] | None = None,
    discretization: str = "interpolation",
    constraints: tuple = (),
) -> Stops:
    """At every sample of the path, the highest speed from which the robot can still stop within
    ``within`` metres of its platform's travel along the path, keeping every row of
    :func:`path_rows` (its limits and, with ``floor``, its floor) all the way: the question a
    safety case asks. The stop ends at the last sample within the distance; where the path can
    stand still, stopping there is as easy as stopping anywhere before it.

    Exact on the samples: each answer is the top of a controllable set, the backward pass of
    :func:`retime` run from rest at the stop's sample.

    Args:
        within: the distance (m), > 0.
        rows: the path's rows when already computed (:func:`path_rows`), else computed here.
        discretization: as :func:`retime`'s.
        robot, trajectory, task, object_mass, floor, constraints: as :func:`path_rows`.

    Raises:
        ArgumentError: a distance that is not a finite positive number; a path whose platform does
            not move.
    """
    if isinstance(within, bool) or not (isinstance(within, (int, float)) and math.isfinite(within) and within > 0):
        raise ArgumentError(f"the stopping distance must be a finite positive number of metres, got {within!r}")
    distance, rates = _base_distance(robot, trajectory)
    if distance[-1] <= 0.0:
        raise ArgumentError("the path's platform does not move: a stopping distance along it means nothing")
    if rows is None:
        rows = path_rows(robot, trajectory, task, object_mass=object_mass, floor=floor, constraints=constraints)
    polygons = [_polygon(r) for r in interval_rows(rows, trajectory.t, discretization)]
    steps = np.diff(trajectory.t)
    n = len(trajectory)
    stop_at = np.minimum(np.searchsorted(distance, distance + within * (1 + 1e-12), side="right") - 1, n - 1)
    speed = np.zeros(n)
    for i in range(n):
        if not polygons[i] or stop_at[i] <= i:
            continue
        top = _stop_bound(polygons, steps, i, int(stop_at[i]))
        speed[i] = math.sqrt(top) if top > 0.0 else 0.0
    return Stops(trajectory.t.copy(), distance, float(within), speed, speed * rates, stop_at, rates)


def _binding(rows: PathRows, a: float, b: float) -> tuple[str, str]:
    """The row nearest to binding at (a, b), relative to its scale."""
    value = rows.ca * a + rows.cb * b
    scale = np.abs(rows.ca * a) + np.abs(rows.cb * b) + np.abs(rows.d)
    scale[scale == 0.0] = 1.0
    k = int(np.argmin((rows.d - value) / scale))
    return rows.labels[k], rows.kinds[k]


def _still_breaks(rows: PathRows) -> str:
    """The rows that standing still (s' = s'' = 0) breaks, by label, or ""."""
    broken = rows.d < -ROW_TOLERANCE * (1.0 + np.abs(rows.d))
    return ", ".join(dict.fromkeys(label for label, bad in zip(rows.labels, broken) if bad))


def _blocking(rows: PathRows, accept=bool) -> str:
    """What leaves the grid point no (s'', s'^2) that ``accept`` takes (by default: none at all):
    the first row (by label) without which it has some, or "its limits together" naming their
    kinds."""
    labels = np.asarray(rows.labels)
    for label in dict.fromkeys(rows.labels):
        keep = labels != label
        polygon = _polygon(PathRows(rows.ca[keep], rows.cb[keep], rows.d[keep], (), ()))
        if polygon and accept(polygon):
            return label
    return "its limits together (" + ", ".join(dict.fromkeys(rows.kinds)) + ")"
