"""Whole-body trajectories: time-stamped configurations, their reduced velocities and accelerations.

A trajectory is N samples (t_i, q_i). Its reduced velocities x_i and accelerations xdot_i are
given, or estimated from the configurations: at each sample a quadratic through the tangent
displacements ``pin.difference(q_i, q_{i-1})`` and ``pin.difference(q_i, q_{i+1})`` gives the joint
rates v_i and accelerations a_i (exact for motions of constant acceleration in the tangent space,
and for any time grid; a planar root's displacement comes from :func:`planar_log`, which keeps
yaw changes too small for ``pin.difference``), then ``x = S^+ v`` and ``xdot = S^+ (a - Sdot x)`` over the rows the file
determines. Scaling every time stamp by 1/k scales the estimates by exactly k and k^2.

The CSV form has a header: ``t`` (s), ``platform_x``, ``platform_y`` (m), ``platform_yaw`` (rad), then
one column per moving joint named as in q.json (rad or m); joints without a column stay at their
home position and, if they are wheels, their rates follow from the platform's motion. The
columns of :data:`ANNOTATION_COLUMNS` are allowed and ignored.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ArgumentError, JointNotFoundError
from ..robot.model import Robot

PLATFORM_COLUMNS = ("platform_x", "platform_y", "platform_yaw")
#: How much a fixed platform's pose columns may vary over a trajectory's rows (m or rad): rounding.
PLATFORM_STILL = 1e-9
#: Columns a trajectory file may carry beside the configuration (``mobmanip carry`` writes them);
#: they are not read.
ANNOTATION_COLUMNS = ("capacity", "baseline_capacity", "tracking_error")


@dataclass(frozen=True)
class Trajectory:
    """A sampled whole-body motion.

    Attributes:
        t: time stamps (s), strictly increasing, (N,).
        q: configurations, (N, nq).
        x: reduced velocities, (N, nx).
        xdot: reduced accelerations, (N, nx).
        slip: per sample, the norm of the joint rates the reduced velocities cannot produce,
            ``|v - S x|`` over the rows used (m/s, rad/s): the platform's lateral slip for a
            differential drive; 0 for a trajectory given by its x, (N,).
    """

    t: np.ndarray
    q: np.ndarray
    x: np.ndarray
    xdot: np.ndarray
    slip: np.ndarray

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def scaled(self, factor: float) -> Trajectory:
        """The same path run ``factor`` times faster: time stamps divided by it, velocities
        multiplied by it and accelerations by its square (what re-estimating the rates from the
        configurations at the new time stamps gives, :func:`trajectory_from_samples`)."""
        try:
            factor = float(factor)
        except (TypeError, ValueError):
            factor = math.nan
        if not (math.isfinite(factor) and factor > 0.0):
            raise ArgumentError(f"time-scaling factor must be a finite positive number, got {factor!r}")
        return Trajectory(self.t / factor, self.q, self.x * factor, self.xdot * factor**2, self.slip * factor)


def _check_times(t) -> np.ndarray:
    t = np.asarray(t, dtype=float).reshape(-1)
    if t.shape[0] < 3:
        raise ArgumentError(f"a trajectory needs at least 3 samples, got {t.shape[0]}")
    if not np.all(np.isfinite(t)):
        k = int(np.flatnonzero(~np.isfinite(t))[0])
        raise ArgumentError(f"time stamp {k} is {t[k]!r}")
    steps = np.diff(t)
    if np.any(steps <= 0.0):
        k = int(np.flatnonzero(steps <= 0.0)[0])
        raise ArgumentError(f"time stamps must increase: t[{k + 1}] = {t[k + 1]!r} follows t[{k}] = {t[k]!r}")
    return t


def planar_log(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """The SE(2) logarithm of the planar pose b relative to a: (v_x, v_y, theta) in a's frame.

    Args:
        qa, qb: planar joint configurations (x m, y m, cos yaw, sin yaw), (4,) each.

    The turn is ``atan2`` of the relative rotation's (sin, cos) pair, so a yaw change of 1e-8 rad
    is kept where ``cos(yaw)`` rounds to 1 (``pin.difference`` reads 0 there); the translation
    is ``V(theta)^-1 R_a^T (p_b - p_a)`` with the series of ``(theta/2) cot(theta/2)`` near 0.
    """
    ca, sa, cb, sb = qa[2], qa[3], qb[2], qb[3]
    theta = math.atan2(ca * sb - sa * cb, ca * cb + sa * sb)
    dx, dy = qb[0] - qa[0], qb[1] - qa[1]
    tx, ty = ca * dx + sa * dy, -sa * dx + ca * dy
    half = 0.5 * theta
    if abs(theta) < 1e-4:
        a = 1.0 - theta * theta / 12.0 - theta**4 / 720.0
    else:
        a = half / math.tan(half)
    return np.array([a * tx + half * ty, -half * tx + a * ty, theta])


def planar_exp(qa: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """The planar pose reached from qa by the SE(2) displacement xi = (v_x, v_y, theta) in qa's
    frame (the inverse of :func:`planar_log`), as (x, y, cos yaw, sin yaw), (4,).

    Unlike ``pin.integrate`` it keeps the effect of a turn of 1e-8 rad on the translation, so a
    wheeled step with no lateral part leaves none (series of ``sin(t)/t`` and ``(1 - cos t)/t``
    near 0).
    """
    vx, vy, theta = (float(v) for v in xi)
    if abs(theta) < 1e-4:
        sinc = 1.0 - theta * theta / 6.0 + theta**4 / 120.0
        cosc = 0.5 * theta - theta**3 / 24.0
    else:
        sinc, cosc = math.sin(theta) / theta, (1.0 - math.cos(theta)) / theta
    tx, ty = sinc * vx - cosc * vy, cosc * vx + sinc * vy
    ca, sa = qa[2], qa[3]
    c, s = math.cos(theta), math.sin(theta)
    cb, sb = ca * c - sa * s, sa * c + ca * s
    norm = math.hypot(cb, sb)
    return np.array([qa[0] + ca * tx - sa * ty, qa[1] + sa * tx + ca * ty, cb / norm, sb / norm])


def _planar_root(model: pin.Model) -> tuple[slice, slice] | None:
    """The configuration block (4) and tangent block (3) of a planar root joint, or ``None``
    when the root is not planar."""
    root = model.joints[1]
    if root.shortname() != "JointModelPlanar":
        return None
    return slice(root.idx_q, root.idx_q + 4), slice(root.idx_v, root.idx_v + 3)


def tangent_integrate(model: pin.Model, q: np.ndarray, dv: np.ndarray) -> np.ndarray:
    """``pin.integrate(model, q, dv)`` (nq,), with a planar root's block from :func:`planar_exp`."""
    out = pin.integrate(model, q, dv)
    if (planar := _planar_root(model)) is not None:
        iq, iv = planar
        out[iq] = planar_exp(q[iq], dv[iv])
    return out


def tangent_difference(model: pin.Model, qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """``pin.difference(model, qa, qb)`` (nv,), with a planar root's block from :func:`planar_log`."""
    d = pin.difference(model, qa, qb)
    if (planar := _planar_root(model)) is not None:
        iq, iv = planar
        d[iv] = planar_log(qa[iq], qb[iq])
    return d


def tangent_derivatives(robot: Robot, t: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint rates v (N, nv) and accelerations a (N, nv) of sampled configurations (module doc).

    Args:
        robot: the loaded robot.
        t: strictly increasing time stamps (s), (N,), N >= 3.
        q: configurations, (N, nq).
    """
    model = robot.model
    n = t.shape[0]
    v = np.zeros((n, model.nv))
    a = np.zeros((n, model.nv))
    for i in range(1, n - 1):
        h1, h2 = t[i] - t[i - 1], t[i + 1] - t[i]
        dm = tangent_difference(model, q[i], q[i - 1])
        dp = tangent_difference(model, q[i], q[i + 1])
        den = h1 * h2 * (h1 + h2)
        v[i] = (h1 * h1 * dp - h2 * h2 * dm) / den
        a[i] = 2.0 * (h1 * dp + h2 * dm) / den
    for end, near, sign in ((0, 1, 1.0), (n - 1, n - 2, -1.0)):
        h = abs(t[near] - t[end])
        d = tangent_difference(model, q[end], q[near])
        a[end] = a[near]
        v[end] = sign * (d / h - 0.5 * a[near] * h)
    return v, a


def trajectory_from_samples(
    robot: Robot,
    t: Sequence[float] | np.ndarray,
    q: np.ndarray,
    x: np.ndarray | None = None,
    xdot: np.ndarray | None = None,
    *,
    known_joints: Sequence[str] | None = None,
) -> Trajectory:
    """A trajectory from time stamps and configurations, with its velocities given or estimated.

    Args:
        robot: the loaded robot.
        t: time stamps (s), strictly increasing, (N,), N >= 3.
        q: configurations, (N, nq).
        x, xdot: reduced velocities and accelerations, (N, nx) each; both or neither (then
            estimated, see the module doc).
        known_joints: the joints whose positions the configurations give (default all); the
            rates of the others (e.g. wheels a file has no column for) follow from the rest
            through S. The platform's pose is always given.

    Raises:
        ArgumentError: fewer than 3 samples, time stamps that do not increase, bad shapes.
        ConfigurationError: a configuration of the wrong size or out of range.
    """
    from ..batch import check_configurations

    t = _check_times(t)
    q = check_configurations(robot, np.asarray(q, dtype=float))
    if q.shape[0] != t.shape[0]:
        raise ArgumentError(f"{t.shape[0]} time stamps but {q.shape[0]} configurations")
    n = t.shape[0]
    if (x is None) != (xdot is None):
        raise ArgumentError("give both the reduced velocities x and accelerations xdot, or neither")
    if x is not None:
        x, xdot = (np.asarray(a, dtype=float) for a in (x, xdot))
        for name, array in (("x", x), ("xdot", xdot)):
            if array.shape != (n, robot.nx) or not np.all(np.isfinite(array)):
                raise ArgumentError(f"{name} must be finite numbers of shape ({n}, {robot.nx}), got {array.shape}")
        return Trajectory(t, q, x, xdot, np.zeros(n))
    v, a = tangent_derivatives(robot, t, q)
    rows = _known_rows(robot, known_joints)
    x = np.zeros((n, robot.nx))
    xdot = np.zeros((n, robot.nx))
    slip = np.zeros(n)
    for i in range(n):
        S = robot.null_space(q[i])[rows]
        S_pinv = np.linalg.pinv(S)
        x[i] = S_pinv @ v[i, rows]
        slip[i] = float(np.linalg.norm(v[i, rows] - S @ x[i]))
        sdot_x = robot.null_space_rate(q[i], x[i])[rows] @ x[i]
        xdot[i] = S_pinv @ (a[i, rows] - sdot_x)
    return Trajectory(t, q, x, xdot, slip)


def moving_joint_names(robot: Robot) -> tuple[str, ...]:
    """The joints a trajectory file has columns for: every joint of the model but the root."""
    return robot.joint_names


def read_trajectory(robot: Robot, path: str | Path) -> Trajectory:
    """A trajectory from a CSV file (module doc for the columns).

    Raises:
        ArgumentError: unreadable file, missing ``t``/platform columns, a non-numeric cell,
            too few samples or time stamps that do not increase (naming the row and column).
        JointNotFoundError: a column that is not a joint of the robot.
    """
    from ..support.ranges import JOINT_POSITION, PLATFORM_POSITION
    from ..support.reading import TIME_STAMP, check_time_stamps, parse_csv_body, read_csv_header

    path = Path(path)
    header, body = read_csv_header(path, "trajectory")
    for needed in ("t",) + PLATFORM_COLUMNS:
        if needed not in header:
            raise ArgumentError(f"trajectory {path}: no column {needed!r} in the header {header}")
    if len(set(header)) != len(header):
        raise ArgumentError(f"trajectory {path}: repeated column names in the header {header}")
    skip = {"t", *PLATFORM_COLUMNS, *ANNOTATION_COLUMNS}
    joints = [name for name in header if name not in skip]
    known = set(robot.joint_names)
    for name in joints:
        if name not in known:
            raise JointNotFoundError(name, robot.joint_names, where=f"robot {robot.name} (trajectory {path})")
    bounds = {"t": (TIME_STAMP, "s"), PLATFORM_COLUMNS[0]: (PLATFORM_POSITION, "m"),
              PLATFORM_COLUMNS[1]: (PLATFORM_POSITION, "m")}  # fmt: skip

    def bound_of(name: str) -> tuple[float, str]:
        return bounds.get(name, (JOINT_POSITION if name in known else math.inf, ""))

    values = parse_csv_body(path, "trajectory", header, body, bound_of)
    check_time_stamps(values[:, header.index("t")], f"trajectory {path}", [i for i, _ in body])
    column = {name: values[:, k] for k, name in enumerate(header)}
    if robot.platform_locked:
        _check_platform_still(robot, path, column)
    qs = np.array(
        [
            robot.configuration(
                (
                    float(column[PLATFORM_COLUMNS[0]][i]),
                    float(column[PLATFORM_COLUMNS[1]][i]),
                    float(column[PLATFORM_COLUMNS[2]][i]),
                ),
                {name: column[name][i] for name in joints},
            )
            for i in range(values.shape[0])
        ]
    )
    return trajectory_from_samples(robot, column["t"], qs, known_joints=joints)


def _check_platform_still(robot: Robot, path: Path, column: Mapping[str, np.ndarray]) -> None:
    """Refuse a trajectory that moves a fixed platform: its pose columns say where the robot is
    mounted, and a motion of them is no joint's (it read as slip, and a retiming found nothing
    limiting the speed of a path whose joints all stand still)."""
    for name in PLATFORM_COLUMNS:
        values = column[name]
        spread = float(np.max(values) - np.min(values))
        if spread > PLATFORM_STILL:
            unit = "rad" if name == "platform_yaw" else "m"
            raise ArgumentError(
                f"trajectory {path}: robot {robot.name!r} has a fixed platform, but {name} changes by "
                f"{spread:.6g} {unit} over the rows; a fixed platform stays where it is mounted (keep "
                f"{', '.join(PLATFORM_COLUMNS)} constant)"
            )


def _known_rows(robot: Robot, known_joints: Sequence[str] | None) -> np.ndarray:
    """Tangent rows of the root joint and of the joints named (all joints when ``None``)."""
    model = robot.model
    if known_joints is None:
        return np.arange(model.nv)
    known = set(known_joints)
    for name in known:
        if name not in robot.joint_names:
            raise JointNotFoundError(name, robot.joint_names, where=f"robot {robot.name}")
    return np.array(
        [
            v
            for j in range(1, model.njoints)
            if j == 1 or model.names[j] in known
            for v in range(model.joints[j].idx_v, model.joints[j].idx_v + model.joints[j].nv)
        ]
    )


def trajectory_table(robot: Robot, t: np.ndarray, qs: np.ndarray) -> tuple[list[str], np.ndarray]:
    """The CSV columns of configurations: header and values (N, 4 + joints)."""
    header = ["t", *PLATFORM_COLUMNS, *moving_joint_names(robot)]
    rows = []
    for ti, q in zip(t, qs):
        d = robot.configuration_dict(q)
        rows.append([float(ti), *d["platform"], *(d["joints"][name] for name in moving_joint_names(robot))])
    return header, np.array(rows)
