"""Move with capacity: a whole-body motion that carries the held object along a path.

One quadratic program per time step over the reduced velocities x (wheel rates and joint
rates, so the platform's nonholonomic constraints hold exactly: v = S x has no lateral slip)::

    minimise    1/2 x^T D^-2 x - w (S^T grad f(q))^T x       (D = diag(xdot_max))
    subject to  J_u(q) x = b                                   (the hands follow the object)
                max(-xdot_max, (q_lo - q) / T) <= x <= min(xdot_max, (q_hi - q) / T)
                |tau(q, x_prev, (x - x_prev) / dt)| <= 0.99 tau_max    (wheel and joint efforts)

where T = max(dt, :data:`LIMIT_HORIZON`) (a joint slows down smoothly near a position limit)
and tau is the efforts of the paper's policy (:meth:`mobmanip.motion.MotionTerms.torques`),
affine in x with the velocity terms taken at the previous step's rates x_prev (the 1% margin
covers that). Without the effort rows a switch of the climbed gradient (e.g. when two
semi-axes cross) once asked 1.5 times a wheel's effort limit in a single step. q advances by
``pin.integrate(q, S x dt)`` (the platform's pose by the exact SE(2) exponential,
:func:`mobmanip.motion.trajectory.planar_exp`). The hands keep the grasp of the start posture: hand i's
target pose at the next step is the object's path applied to its start pose (the
object translates along the path and turns about the vertical by the path's change of heading,
or by its ``yaw`` column), and b is the task velocity that reaches it in one step, so tracking
errors do not accumulate. f is the chosen measure (:mod:`mobmanip.gradients`, at rest); w is
fixed at the first step so that the capacity term alone would move at half the velocity limits
(in the D-weighted norm). The baseline tracks the same targets with the weighted pseudo-inverse
``x = D^2 J_u^T (J_u D^2 J_u^T)^-1 b`` (no capacity term, no limits).

The start. Many postures hold the object at the path's start (the redundancy), and the minimum
capacity along a path is often the start's. So the capacity-aware motion first moves to a
better one: a *self-motion* before the path starts, the same QP with the object held still
(the hands' targets are their start poses), run until the objective rises by less than
:data:`PREPARE_TOLERANCE` (relative) over :data:`PREPARE_WINDOW` seconds or for at most
``prepare`` seconds (:attr:`CarryResult.preparation`). The path's motion starts where it ends;
the baseline starts from the given (or default) start posture, as a controller without a
capacity term would.

The path (CSV, :func:`read_path`) has ``t`` and the object's ``x``, ``y`` (m) and optionally ``z``
(m) and ``yaw`` (rad); by default it is relative to where the start posture holds the object.
Between its samples the path is a cubic spline in time (:meth:`ObjectPath.sample`), so the
object's acceleration is continuous: interpolated linearly, a path sampled every 0.1 s and
tracked every 0.02 s asked for an impulse of acceleration at each sample and none between.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import ArgumentError, CarryFailed, MeasureError, SpecError
from ..gradients.evaluator import Objective
from ..gradients.readings import ReadingObjective, objective_evaluator
from ..postures.planar import optimal_configuration
from ..robot.model import Robot
from ..robot.tasks import get_task
from ..support.progress import progress_bar
from ..terms.builder import terms_at
from .carry_floor import NO_TURN, CarryFloor, floor_binding, floor_rows, solve_with_floor
from .carry_step import EFFORT_SHARE as EFFORT_SHARE
from .carry_step import LIMIT_HORIZON as LIMIT_HORIZON
from .carry_step import CarryDiagnosis as CarryDiagnosis
from .carry_step import _effort_map, diagnose_step, effort_rows_of, solve_step_qp, velocity_bounds
from .step_constraints import StepRows, check_constraints, step_rows
from .trajectory import tangent_integrate

PATH_COLUMNS = ("t", "x", "y", "z", "yaw")
#: Default time step of the synthesis (s).
DEFAULT_STEP = 0.02
#: The capacity term's share of the velocity limits at the first step.
DEFAULT_GAIN = 0.5
#: Time stamps of the synthesised motions are rounded to this many decimals (ns): the step's
#: multiples then print as written (6.02, not 6.0200000000000005).
TIME_DECIMALS = 9
#: Longest self-motion before the path (s); 0 starts the path from the start posture.
DEFAULT_PREPARE = 30.0
#: The self-motion stops when the objective rose by less than this fraction of its value ...
PREPARE_TOLERANCE = 1e-4
#: ... over this long (s).
PREPARE_WINDOW = 1.0


#: Below this speed (m/s) a path's end counts as at rest (:meth:`ObjectPath.moving_ends`).
REST_SPEED = 1e-3


@dataclass(frozen=True)
class ObjectPath:
    """Where the object should be over time.

    Attributes:
        t: time stamps (s), strictly increasing, (N,).
        xy: positions (m), (N, 2); z: heights (m), (N,) or ``None``; yaw: headings (rad), (N,)
            or ``None`` (then the object turns with the path's direction of travel).
    """

    t: np.ndarray
    xy: np.ndarray
    z: np.ndarray | None = None
    yaw: np.ndarray | None = None

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.shape[0] < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise ArgumentError("an object path needs at least 2 finite, strictly increasing time stamps")
        xy = np.asarray(self.xy, dtype=float)
        if xy.shape != (t.shape[0], 2) or not np.all(np.isfinite(xy)):
            raise ArgumentError(f"object path positions must be finite, shape ({t.shape[0]}, 2), got {xy.shape}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "xy", xy)
        for name in ("z", "yaw"):
            value = getattr(self, name)
            if value is not None:
                value = np.asarray(value, dtype=float)
                if value.shape != t.shape or not np.all(np.isfinite(value)):
                    raise ArgumentError(f"object path {name} must be {t.shape[0]} finite numbers")
                object.__setattr__(self, name, value)

    def length(self) -> float:
        """Length of the path in the plane (m)."""
        return float(np.sum(np.linalg.norm(np.diff(self.xy, axis=0), axis=1)))

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Displacement from the start (N, 3) (m) and turn from the start (N,) (rad) at ``times``.

        Between the path's samples each coordinate follows a cubic spline in time through them
        (:func:`smooth`: twice continuously differentiable, so the object's acceleration is
        continuous; linear interpolation made it an impulse at every sample and zero between).
        Times outside the path hold its ends.
        """
        times = np.clip(np.asarray(times, dtype=float), self.t[0], self.t[-1])
        d = np.zeros((len(times), 3))
        d[:, 0] = smooth(self.t, self.xy[:, 0], times) - self.xy[0, 0]
        d[:, 1] = smooth(self.t, self.xy[:, 1], times) - self.xy[0, 1]
        if self.z is not None:
            d[:, 2] = smooth(self.t, self.z, times) - self.z[0]
        if self.yaw is not None:
            turn = smooth(self.t, np.unwrap(self.yaw), times) - self.yaw[0]
        else:
            turn = self._heading_turn(times)
        return d, turn

    def end_speeds(self) -> tuple[float, float]:
        """The object's speed (m/s, in space) at the path's start and at its end, as
        :meth:`sample` moves it: the derivative of its splines there."""
        coordinates = [self.xy[:, 0], self.xy[:, 1]] + ([self.z] if self.z is not None else [])
        rates = np.array([_end_rates(self.t, values) for values in coordinates])  # (coordinates, 2)
        start, end = np.linalg.norm(rates, axis=0)
        return float(start), float(end)

    def moving_ends(self, step: float, rest_speed: float = REST_SPEED) -> list[str]:
        """A sentence for each end of the path at which the object still moves (its speed above
        ``rest_speed``, m/s): a motion sampled every ``step`` seconds starts or stops the object
        within one step there, an acceleration of about speed / step no robot gives.

        Raises:
            ArgumentError: ``step`` or ``rest_speed`` not a positive finite number.
        """
        for name, value in (("step", step), ("rest speed", rest_speed)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < math.inf:
                raise ArgumentError(f"the {name} must be a positive number, got {value!r}")
        out = []
        for speed, time_s, verb, noun in zip(self.end_speeds(), (self.t[0], self.t[-1]), ("starts", "ends"),
                                             ("start", "stop")):  # fmt: skip
            if speed > rest_speed:
                out.append(
                    f"the object path {verb} moving, at {speed:.3g} m/s (t = {time_s:g} s): the motion makes its "
                    f"{noun} within one step of {step:g} s, about {speed / step:.3g} m/s^2; let the path's "
                    f"samples bring it to rest there (as examples/carry_turn.csv does)"
                )
        return out

    def _heading_turn(self, times: np.ndarray) -> np.ndarray:
        steps = np.diff(self.xy, axis=0)
        moving = np.linalg.norm(steps, axis=1) > 1e-12
        if not moving.any():
            return np.zeros(len(times))
        heading = np.arctan2(steps[:, 1], steps[:, 0])
        first = heading[moving][0]
        heading = np.where(moving, heading, np.nan)
        # hold the last heading through pauses, then unwrap
        for k in range(len(heading)):
            if np.isnan(heading[k]):
                heading[k] = first if k == 0 else heading[k - 1]
        heading = np.unwrap(heading)
        mids = 0.5 * (self.t[1:] + self.t[:-1])
        return smooth(mids, heading, np.clip(times, mids[0], mids[-1])) - heading[0]


def _end_rates(t: np.ndarray, values: np.ndarray) -> tuple[float, float]:
    """d values / dt at t[0] and t[-1] of :func:`smooth`'s curve through them."""
    from scipy.interpolate import CubicSpline

    if t.shape[0] == 2:
        rate = float((values[1] - values[0]) / (t[1] - t[0]))
        return rate, rate
    slope = CubicSpline(t, values).derivative()
    return float(slope(t[0])), float(slope(t[-1]))


def smooth(t: np.ndarray, values: np.ndarray, times: np.ndarray) -> np.ndarray:
    """values (N,) given at t (N,) evaluated at ``times`` inside [t[0], t[-1]] by a cubic spline
    in time (SciPy's ``CubicSpline``, not-a-knot ends: C2, exact for cubic motions); two
    samples give the straight line between them, one its value."""
    from scipy.interpolate import CubicSpline

    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float)
    if t.shape[0] == 1:
        return np.full(np.shape(times), float(values[0]))
    if t.shape[0] == 2:
        return np.interp(times, t, values)
    return CubicSpline(t, values)(times)


def read_path(path: str | Path) -> ObjectPath:
    """An object path from CSV with a header ``t,x,y[,z][,yaw]``.

    Raises:
        ArgumentError: unreadable file, unknown or missing columns, a cell that is not a finite
            number (naming line and column), too few rows or time stamps that do not increase.
    """
    from ..support.ranges import PLATFORM_POSITION
    from ..support.reading import TIME_STAMP, check_time_stamps, parse_csv_body, read_csv_header

    path = Path(path)
    header, body = read_csv_header(path, "object path")
    unknown = [c for c in header if c not in PATH_COLUMNS]
    if unknown or not {"t", "x", "y"} <= set(header) or len(set(header)) != len(header):
        raise ArgumentError(f"object path {path}: header {header} must name t, x, y and optionally z, yaw (each once)")
    bounds = {"t": (TIME_STAMP, "s"), "yaw": (1e4, "rad")}
    values = parse_csv_body(path, "object path", header, body, lambda name: bounds.get(name, (PLATFORM_POSITION, "m")))
    if "t" in header:
        check_time_stamps(values[:, header.index("t")], f"object path {path}", [i for i, _ in body])
    col = {name: values[:, k] for k, name in enumerate(header)}
    try:
        return ObjectPath(col["t"], np.column_stack([col["x"], col["y"]]), col.get("z"), col.get("yaw"))
    except ArgumentError as exc:
        raise ArgumentError(f"object path {path}: {exc}") from None


@dataclass(frozen=True)
class CarryRun:
    """One synthesised motion.

    Attributes:
        method: ``"qp"`` (capacity-maximising), ``"pinv"`` (the weighted pseudo-inverse baseline) or
            ``"self-motion"`` (the QP with the object held still, before the path).
        t: time stamps (s), (N,).
        q: configurations, (N, nq).
        x: reduced velocities held over each step [t_k, t_k+1], (N - 1, nx).
        capacity: the objective's value at each configuration, (N,).
        tracking_error: distance of the object's centre from its path (m), (N,).
        hand_error: largest distance of a hand from its target position (m), (N,).
    """

    method: str
    t: np.ndarray
    q: np.ndarray
    x: np.ndarray
    capacity: np.ndarray
    tracking_error: np.ndarray
    hand_error: np.ndarray


@dataclass(frozen=True)
class CarryResult:
    """The capacity-maximising motion and the baseline along the same path.

    Attributes:
        objective: the measure maximised (and reported as capacity).
        task: task space name.
        motion: the QP motion along the path; baseline: the pseudo-inverse one.
        preparation: the self-motion that took the start posture to ``motion``'s first
            configuration (time stamps ending at the path's start), or ``None`` when the motion
            starts from the start posture (``prepare=0``).
        start: which start posture both runs set out from, in words.
        prepared_baseline: the pseudo-inverse baseline from the QP's prepared start (the end of
            the self-motion), or ``None`` without a self-motion: with it the gain splits into
            what the preparation gives and what the motion gives (:meth:`summary`).
        collapsed: per run (``"qp"``, ``"pinv"``, ``"pinv_prepared"``), the objective's set at
            the run's minimum as its smallest and largest semi-axes when it has collapsed there
            (:func:`mobmanip.analysis.plausibility.collapsed`: a singular posture); a ratio to
            that minimum is not reported.
        floor: the floor the QP motion kept (:meth:`CarryFloor.describe`), or ``None``.
        constraints: the other constraints it kept, as described in JSON.
    """

    objective: Objective | ReadingObjective
    task: str
    motion: CarryRun
    baseline: CarryRun
    preparation: CarryRun | None = None
    start: str = "the given start configuration"
    prepared_baseline: CarryRun | None = None
    collapsed: dict[str, tuple[float, float]] = field(default_factory=dict)
    floor: dict | None = None
    constraints: tuple[dict, ...] = ()

    def starts(self) -> dict:
        """What each run started from, in words and numbers (JSON-ready)."""
        base = {
            "posture": self.start,
            "capacity": float(self.baseline.capacity[0]),
        }
        prep = self.preparation
        if prep is None:
            qp = dict(base)
        else:
            qp = {
                "posture": f"the end of a self-motion from {self.start} with the object held still",
                "capacity": float(self.motion.capacity[0]),
                "self_motion_seconds": float(prep.t[-1] - prep.t[0]),
                "self_motion_start_capacity": float(prep.capacity[0]),
                "self_motion_max_hand_error": float(prep.hand_error.max()),
                "self_motion_max_tracking_error": float(prep.tracking_error.max()),
            }
        return {"qp": qp, "pinv": base}

    def summary(self) -> dict:
        """Minimum capacities, their ratios, tracking and limit figures (JSON-ready).

        ``min_capacity_ratio`` is the QP's minimum over the baseline's from the start posture;
        with a self-motion, ``ratio_parts`` splits it: ``preparation`` (the baseline from the
        QP's prepared start over the baseline from the start posture: what starting from a better
        posture gives) and ``motion`` (the QP over the baseline from the prepared start: what the
        capacity term gives along the path); their product is the whole ratio. A ratio whose
        denominator's set has collapsed (a singular posture) is ``None`` and ``collapsed`` says
        which run and its semi-axes there. ``mean_capacity_ratio`` is the QP's mean over the
        baseline's (from the start posture), the motion's gain where both are least at the start.
        """
        out: dict[str, Any] = {"objective": self.objective.name, "task": self.task}
        runs = {"qp": self.motion, "pinv": self.baseline}
        if self.prepared_baseline is not None:
            runs["pinv_prepared"] = self.prepared_baseline
        for key, run in runs.items():
            out[key] = {
                "min_capacity": float(run.capacity.min()),
                "mean_capacity": float(run.capacity.mean()),
                "max_tracking_error": float(run.tracking_error.max()),
                "max_hand_error": float(run.hand_error.max()),
            }
        for method, start in self.starts().items():
            out[method]["start"] = start
        if self.prepared_baseline is not None:
            out["pinv_prepared"]["start"] = dict(out["qp"]["start"])

        def ratio(top: str, bottom: str, of=np.min) -> float | None:
            low = of(runs[bottom].capacity)
            if low <= 0 or bottom in self.collapsed:
                return None
            return float(of(runs[top].capacity) / low)

        out["min_capacity_ratio"] = ratio("qp", "pinv")
        out["mean_capacity_ratio"] = ratio("qp", "pinv", np.mean)
        if self.prepared_baseline is not None:
            out["ratio_parts"] = {"preparation": ratio("pinv_prepared", "pinv"), "motion": ratio("qp", "pinv_prepared")}
        out["collapsed"] = {
            key: {"smallest_semi_axis": a, "largest_semi_axis": b} for key, (a, b) in self.collapsed.items()
        }
        if self.floor is not None:
            out["floor"] = self.floor
        if self.constraints:
            out["constraints"] = [dict(c) for c in self.constraints]
        return out


class _Targets:
    """Hands' target poses along the path (see the module doc)."""

    def __init__(self, robot: Robot, q0: np.ndarray, path: ObjectPath, times: np.ndarray):
        model, data = robot.model, robot.data
        pin.framesForwardKinematics(model, data, q0)
        self.start = [data.oMf[arm.frame_id].copy() for arm in robot.arms]
        self.center0 = np.mean([m.translation for m in self.start], axis=0)
        self.shift, self.turn = path.sample(times)

    def object_center(self, k: int) -> np.ndarray:
        return self.center0 + self.shift[k]

    def hand(self, k: int, i: int) -> pin.SE3:
        R = pin.rpy.rpyToMatrix(0.0, 0.0, float(self.turn[k]))
        start = self.start[i]
        return pin.SE3(R @ start.rotation, self.object_center(k) + R @ (start.translation - self.center0))


def _hand_rates(robot: Robot, q: np.ndarray, targets: _Targets, k: int, dt: float, rows: list[int]) -> np.ndarray:
    """Stacked task velocities that bring each hand from its pose at q to its target at step k."""
    data = robot.data
    out = []
    for i, arm in enumerate(robot.arms):
        now = data.oMf[arm.frame_id]
        goal = targets.hand(k, i)
        twist = np.concatenate([goal.translation - now.translation, pin.log3(goal.rotation @ now.rotation.T)])
        out.append(twist[rows] / dt)
    return np.concatenate(out)


def _errors(robot: Robot, targets: _Targets, k: int) -> tuple[float, float]:
    """(object centre error, largest hand position error) from ``robot.data``'s placements (m)."""
    data = robot.data
    positions = np.array([data.oMf[arm.frame_id].translation for arm in robot.arms])
    hand = max(float(np.linalg.norm(positions[i] - targets.hand(k, i).translation)) for i in range(len(robot.arms)))
    return float(np.linalg.norm(positions.mean(axis=0) - targets.object_center(k))), hand


def default_start(robot: Robot) -> np.ndarray:
    """The spec's hold posture; for the paper's robot without one, its case-study posture with
    the object straight ahead (both arms at their own optimum,
    :func:`mobmanip.postures.planar.optimal_configuration`); else the home configuration."""
    if robot.spec.hold:
        return robot.hold_configuration()
    try:
        return optimal_configuration(robot, 0.0)
    except SpecError:
        return robot.neutral()


def _default_start_label(robot: Robot, q0: np.ndarray) -> str:
    if robot.spec.hold:
        return "the spec's hold posture"
    if np.array_equal(q0, robot.neutral()):
        return "the home configuration"
    return "the case-study posture (both arms at their optimum, object straight ahead)"


def _why_undefined(evaluator) -> str:
    dynamic = getattr(evaluator.objective, "ellipsoid", None) == "dynamic"
    return "the posture is singular there" + (" or the torques cannot hold the load" if dynamic else "")


#: The runs as a message names them.
_RUN_NAMES = {"qp": "QP motion", "pinv": "baseline", "self-motion": "self-motion"}


def _run(
    robot,
    q0,
    path,
    evaluator,
    task,
    dt,
    method,
    gain,
    weight=None,
    converge=False,
    object_mass=None,
    x_start=None,
    floor=None,
    progress=False,
    constraints=(),
) -> tuple[CarryRun, float]:
    """One motion along ``path`` from ``q0``; returns it and the capacity term's weight used.
    ``converge`` stops early once the objective rises by less than :data:`PREPARE_TOLERANCE`
    over :data:`PREPARE_WINDOW` (the self-motion). ``x_start``: the reduced velocity before the
    first step (default rest), from which the first step's efforts are counted."""
    model = robot.model
    n = int(math.floor((path.t[-1] - path.t[0]) / dt + 1e-9)) + 1
    times = np.round(path.t[0] + dt * np.arange(n), TIME_DECIMALS)  # 6.02, not 6.0200000000000005
    if times[-1] < path.t[-1] - 1e-12:
        times = np.append(times, path.t[-1])
        n += 1
    targets = _Targets(robot, q0, path, times)
    rows = list(task.rows)
    D2 = np.asarray(robot.velocity_limits, dtype=float) ** 2
    H = np.diag(1.0 / D2)
    qs = np.zeros((n, model.nq))
    xs = np.zeros((n - 1, robot.nx))
    capacity, track, hand = np.zeros(n), np.zeros(n), np.zeros(n)
    q = q0.copy()
    x_prev = np.zeros(robot.nx) if x_start is None else np.asarray(x_start, dtype=float)
    effort_limits = np.asarray(robot.effort_limits, dtype=float)
    window = max(1, int(round(PREPARE_WINDOW / dt)))
    resolved = None if floor is None or method == "pinv" else floor.resolve(robot)
    # on a ramp the efforts hold the leaning weights too (the floor's axes are the world's)
    gravity = None if resolved is None or not floor.slope else floor.gravity()
    with progress_bar(n, desc=f"carry {method}", unit="step", show=progress) as bar:
        for k in range(n):
            bar.update(1)
            qs[k] = q
            value, grad, ok = evaluator(q)
            if not ok:
                raise MeasureError(
                    f"{evaluator.objective.name} is not defined at step {k} (t = {times[k]:g} s) of the "
                    f"{_RUN_NAMES[method]}: {_why_undefined(evaluator)}"
                )
            capacity[k] = value
            S = robot.null_space(q)
            J_u = _jacobian(robot, q, rows) @ S  # also updates the frame placements
            track[k], hand[k] = _errors(robot, targets, k)
            if converge and k >= window and capacity[k] - capacity[k - window] < PREPARE_TOLERANCE * abs(capacity[k]):
                n = k + 1
                break
            if k == n - 1:
                break
            h = times[k + 1] - times[k]
            b = _hand_rates(robot, q, targets, k + 1, h, rows)
            if method == "pinv":
                x = D2 * (J_u.T @ np.linalg.solve((J_u * D2) @ J_u.T, b))
            else:
                g = S.T @ grad
                if weight is None:
                    norm = float(np.linalg.norm(np.sqrt(D2) * g))
                    weight = gain / norm if norm > 0 else 0.0
                lo, hi = velocity_bounds(robot, q, h)
                effort_map = _effort_map(robot, q, x_prev, h, task, object_mass, gravity)
                G, g_hi = effort_rows_of(effort_map, effort_limits)
                extra = None
                if constraints:
                    at_rest = terms_at(robot, q, task.name, object_mass=object_mass, check=False)
                    extra = step_rows(constraints, at_rest, x_prev, h, effort_map)
                    G, g_hi = np.vstack([G, extra.G]), np.concatenate([g_hi, extra.h])
                if resolved is None:
                    x = solve_step_qp(H, -weight * g, J_u, b, lo, hi, G, g_hi)
                else:
                    floor_G, floor_g, labels = floor_rows(robot, q, x_prev, h, task, object_mass, floor, resolved)
                    x = solve_with_floor(solve_step_qp, H, -weight * g, J_u, b, lo, hi, G, g_hi, floor_G, floor_g)
                if x is None:
                    binding = None
                    if resolved is not None:
                        binding = floor_binding(
                            solve_step_qp, H, -weight * g, J_u, b, lo, hi, G, g_hi, floor_G, floor_g, labels
                        )
                    constraint = None if extra is None else _binding_constraint(H, -weight * g, J_u, b, lo, hi, G, g_hi,
                                                                              extra)  # fmt: skip
                    if binding is not None:
                        helps = binding != NO_TURN  # a turn the base cannot make is no matter of speed
                        diagnosis = CarryDiagnosis(k, float(times[k]), binding, "floor", slowing_helps=helps)
                    elif constraint is not None:
                        diagnosis = CarryDiagnosis(k, float(times[k]), constraint, "constraint")
                    else:
                        diagnosis = diagnose_step(robot, q, h, effort_map, J_u, b, k, float(times[k]))
                    if method == "self-motion":
                        diagnosis = dataclasses.replace(diagnosis, self_motion=True, slowing_helps=False)
                    partial = CarryRun(method, times[: k + 1], qs[: k + 1], xs[:k], capacity[: k + 1], track[: k + 1],
                                       hand[: k + 1])  # fmt: skip
                    raise CarryFailed(f"the carry QP has no solution: {diagnosis.message()}", diagnosis, partial)
            xs[k] = x
            x_prev = x
            q = tangent_integrate(model, q, S @ x * h)
    run = CarryRun(method, times[:n], qs[:n], xs[: n - 1], capacity[:n], track[:n], hand[:n])
    return run, (0.0 if weight is None else weight)


def _binding_constraint(H, c, J_u, b, lo, hi, G, g_hi, extra: StepRows) -> str | None:
    """The label of the given constraints' row the step breaks most without them (at the step
    solved with the robot's own limits only), or ``None`` when it has no solution without them
    either."""
    own = len(g_hi) - len(extra.h)
    x = solve_step_qp(H, c, J_u, b, lo, hi, G[:own], g_hi[:own])
    if x is None:
        return None
    return extra.labels[int(np.argmax(extra.G @ x - extra.h))]


def _jacobian(robot: Robot, q: np.ndarray, rows: list[int]) -> np.ndarray:
    model, data = robot.model, robot.data
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    return np.vstack(
        [pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[rows] for arm in robot.arms]
    )


def check_step_settings(step: float, gain: float, prepare: float) -> None:
    """Refuse a carry's time step (s, in (0, 1]), capacity gain (>= 0) or self-motion time
    (s, >= 0) that is not a finite number in its range (one robot's carry and a team's)."""
    if not (isinstance(step, (int, float)) and math.isfinite(step) and 0.0 < step <= 1.0):
        raise ArgumentError(f"step must be a time in (0, 1] s, got {step!r}")
    if not (isinstance(gain, (int, float)) and math.isfinite(gain) and gain >= 0.0):
        raise ArgumentError(f"gain must be a finite non-negative number, got {gain!r}")
    if not (isinstance(prepare, (int, float)) and math.isfinite(prepare) and prepare >= 0.0):
        raise ArgumentError(f"prepare must be a finite non-negative time (s), got {prepare!r}")


def carry(
    robot: Robot,
    path: ObjectPath,
    objective: Objective | ReadingObjective | str | None = None,
    task: str | None = None,
    *,
    start: np.ndarray | None = None,
    object_mass: float | None = None,
    step: float = DEFAULT_STEP,
    gain: float = DEFAULT_GAIN,
    prepare: float = DEFAULT_PREPARE,
    floor: CarryFloor | None = None,
    constraints: tuple = (),
    progress: bool = False,
) -> CarryResult:
    """Synthesise the capacity-maximising motion along ``path`` and the pseudo-inverse baseline.

    Args:
        robot: the loaded robot; its platform's S must not depend on q (gradients).
        path: the object's path, relative to where ``start`` holds it.
        objective: the measure to maximise: an ellipsoid's index (``ELLIPSOID:INDEX[:DIRECTION]``,
            :class:`Objective`, by its closed-form gradient) or any other registered measure's
            reading (``MEASURE:READING:DIRECTION``, :class:`~mobmanip.gradients.ReadingObjective`,
            by checked central differences: 4 nv + 1 measures a step); default
            ``kinematic:minor_axis``.
        task: task space; default the spec's.
        start: start configuration, (nq,); default :func:`default_start`.
        object_mass: mass of the object held between the hands (kg); default the spec's.
        step: time step (s).
        gain: the capacity term's share of the velocity limits at the first step.
        prepare: longest self-motion (s) before the path (module doc); 0: the QP motion
            starts from ``start`` like the baseline.
        floor: keep the robot on its floor (:class:`mobmanip.motion.carry_floor.CarryFloor`): the
            QP motion's (and the self-motion's) steps keep the zero-moment point inside the
            support polygon with a margin, every support loaded and the driven wheels within
            friction; the baseline does not.
        constraints: constraints of the sets at rest (:mod:`mobmanip.terms.constraints`, e.g. a
            share of the effort limits) kept at every step of the QP motion and the self-motion,
            their rows compiled over the step (:mod:`mobmanip.motion.step_constraints`); the
            baseline ignores them. One that cannot join a step is refused by name.
        progress: show a progress bar per motion on standard error.

    Raises:
        ArgumentError: a bad step, gain or prepare.
        MeasureError: the objective is not defined along a motion (a singular posture).
        CarryFailed: the QP has no solution at some step; the error names the binding limit
            (:class:`CarryDiagnosis`) and holds the part of the motion that succeeded.
    """
    check_step_settings(step, gain, prepare)
    if not isinstance(path, ObjectPath):
        raise ArgumentError(f"path must be an ObjectPath, got {type(path).__name__}")
    if floor is not None and not isinstance(floor, CarryFloor):
        raise ArgumentError(f"floor must be a CarryFloor, got {type(floor).__name__}")
    task = get_task(task or robot.spec.default_task)
    evaluator = objective_evaluator(robot, objective or "kinematic:minor_axis", task, object_mass=object_mass)
    q0 = default_start(robot) if start is None else robot.check_configuration(start)
    constraints = check_constraints(constraints)
    if constraints:  # refused before any work when one cannot join a step
        rest = np.zeros(robot.nx)
        step_rows(constraints, terms_at(robot, q0, task.name, object_mass=object_mass), rest, float(step),
                  (np.zeros((robot.nx, robot.nx)), rest))  # fmt: skip
    label = "the given start configuration" if start is not None else _default_start_label(robot, q0)
    if not evaluator(q0)[2]:
        raise MeasureError(
            f"{evaluator.objective.name} is not defined at the start posture ({label}): {_why_undefined(evaluator)}; "
            "start from another (--start Q.json, or a [hold] posture in the spec)"
        )
    step, gain = float(step), float(gain)
    preparation, weight, q_path = None, None, q0
    if prepare > 0.0 and gain > 0.0:
        still = ObjectPath(np.array([path.t[0] - float(prepare), path.t[0]]), np.zeros((2, 2)))
        preparation, weight = _run(
            robot, q0, still, evaluator, task, step, "self-motion", gain, converge=True, object_mass=object_mass,
            floor=floor, progress=progress, constraints=constraints,
        )  # fmt: skip
        shift = path.t[0] - preparation.t[-1]  # the self-motion ends where the path starts
        preparation = CarryRun(
            preparation.method,
            np.round(preparation.t + shift, TIME_DECIMALS),
            *(getattr(preparation, f) for f in ("q", "x", "capacity", "tracking_error", "hand_error")),
        )
        q_path = preparation.q[-1]
    x_start = None if preparation is None else preparation.x[-1]
    try:
        motion, _ = _run(
            robot, q_path, path, evaluator, task, step, "qp", gain, weight=weight, object_mass=object_mass,
            x_start=x_start, floor=floor, progress=progress, constraints=constraints,
        )  # fmt: skip
    except CarryFailed as exc:
        if exc.partial.method == "qp":
            exc.preparation = preparation
        raise
    baseline, _ = _run(robot, q0, path, evaluator, task, step, "pinv", 0.0, progress=progress)
    prepared = None
    if preparation is not None:  # the same baseline from the QP's prepared start
        prepared, _ = _run(robot, q_path, path, evaluator, task, step, "pinv", 0.0, progress=progress)
    runs = {"qp": motion, "pinv": baseline} | ({} if prepared is None else {"pinv_prepared": prepared})
    found = {
        key: _collapsed_at_minimum(robot, run, evaluator.objective, task.name, object_mass) for key, run in runs.items()
    }
    collapsed = {key: value for key, value in found.items() if value is not None}
    return CarryResult(
        evaluator.objective, task.name, motion, baseline, preparation, label, prepared, collapsed,
        None if floor is None else floor.describe(), tuple(c.describe() for c in constraints),
    )  # fmt: skip


def _collapsed_at_minimum(
    robot: Robot, run: CarryRun, objective: Objective | ReadingObjective, task: str, object_mass: float | None
) -> tuple[float, float] | None:
    """(smallest, largest semi-axis) of the objective's ellipsoid (its block's shadow for a block
    objective) at the run's minimum, when it has collapsed there; else ``None`` (also for a
    reading of another measure: its set has no semi-axes)."""
    from ..analysis.plausibility import collapsed
    from ..analysis.single import analyze

    if not isinstance(objective, Objective):
        return None
    q = run.q[int(np.argmin(run.capacity))]
    task_set = analyze(robot, q, task, object_mass=object_mass).measure(objective.ellipsoid)
    if objective.rows is not None:
        task_set = task_set.project(objective.rows)
    if not collapsed(task_set):
        return None
    semi = np.asarray(getattr(task_set, "semi_axes", [0.0]), dtype=float)
    return float(semi[-1]), float(semi[0])
