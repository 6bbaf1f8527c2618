"""One step of ``carry``'s QP: its bounds and effort rows, and, when it has no solution, which
limit binds (:func:`diagnose_step`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..robot.model import Robot

#: A joint approaches a position limit at most at (distance to the limit) / this (s): it slows
#: down smoothly (exponentially) instead of stopping within one step.
LIMIT_HORIZON = 0.2

#: The QP keeps each step's efforts within this share of their limits (its model takes the
#: velocity terms at the previous step's rates; the margin covers the difference).
EFFORT_SHARE = 0.99


@dataclass(frozen=True)
class CarryDiagnosis:
    """Why a step of the carry QP has no solution.

    Attributes:
        step, t: the step (index) and its time (s).
        joint: the reduced velocity whose limit binds (a wheel or joint name), or ``""`` when no
            single limit does (then ``kind`` names what does).
        kind: ``"position"`` (the joint reaches the end of its range), ``"velocity"``,
            ``"effort"``, ``"floor"`` (a row of ``carry``'s floor: ``joint`` then names it),
            ``"constraint"`` (a row of a constraint given to ``carry``: ``joint`` names it),
            ``"limits together"`` (no single limit: several at once) or
            ``"singular"`` (the hands cannot move as asked at this posture, whatever the limits).
        asked, allowed: for the binding limit, what the step needs and what the limit allows
            (rad/s or m/s for position and velocity, N m or N for effort); ``None`` when no
            single limit binds.
        position, position_limit: for a position limit, the joint's position and the limit it
            reaches (rad or m).
        slowing_helps: whether running the path slower would make the step feasible: no for a
            position limit or a singular posture (the path's geometry asks for it), yes for a
            velocity limit, likely for an effort limit (the accelerations' efforts fall with the
            square of the speed, gravity's do not).
        unit: the unit of ``asked`` and ``allowed`` (``"m/s"``, ``"rad/s"``, ``"N"``, ``"N m"``).
        self_motion: the step is one of the self-motion before the path (the object held
            still): the motion is the capacity term's own, and the path's speed plays no part.
    """

    step: int
    t: float
    joint: str
    kind: str
    asked: float | None = None
    allowed: float | None = None
    position: float | None = None
    position_limit: float | None = None
    slowing_helps: bool | None = None
    unit: str = ""
    self_motion: bool = False

    def message(self) -> str:
        """One sentence for the user."""
        if self.self_motion:
            return (
                f"at step {self.step} of the self-motion before the path (t = {self.t:g} s, the object held still) "
                f"{self._binds()}; this motion is the capacity term's own, not the path's, so slowing the path "
                "down does not help: shorten or skip the self-motion (--prepare S; 0: none)"
            )
        where = f"at step {self.step} (t = {self.t:g} s)"
        if self.kind == "singular":
            return (
                f"{where} the hands cannot move as the path asks at this posture even without limits (a singular "
                "posture); slowing down does not help: change the start posture or the path"
            )
        if self.kind == "floor" and self.slowing_helps is False:
            return (
                f"{where} the floor binds: {self.joint}; the path needs the base to turn here, and slowing down does "
                "not help (give the path a heading the base keeps, or carry it without --ground)"
            )
        if self.kind == "floor":
            return (
                f"{where} the floor binds: {self.joint} cannot hold together with the path and the limits; slowing "
                "the path down likely helps (the floor's forces from the accelerations fall with the speed squared)"
            )
        if self.kind == "constraint":
            return (
                f"{where} a constraint binds: {self.joint}; without it the step has a solution (slowing the path "
                "down may help where the constraint bounds efforts or speeds)"
            )
        if self.kind == "limits together":
            return (
                f"{where} no single limit binds: the velocity, position and effort limits together leave no motion; "
                "slowing the path down may help"
            )
        unit = self.unit or ("N m or N" if self.kind == "effort" else "rad/s or m/s")
        text = f"{where} the {self.kind} limit of {self.joint} binds: the step asks {self.asked:.4g}, the limit allows "
        text += f"{self.allowed:.4g} ({unit})"
        if self.kind == "position":
            return (
                text + f"; the joint is at {self.position:.4g}, its limit {self.position_limit:.4g} "
                f"({self.unit.replace('/s', '') or 'rad or m'}): from this posture the path needs it past the end "
                "of its range, and slowing down does not help; the motion's earlier steps, led one at a time by the "
                "capacity term, brought it here: start from another posture (--start), maximise another objective "
                "or change the path"
            )
        if self.kind == "velocity":
            factor = abs(self.asked or 0.0) / max(abs(self.allowed or 0.0), 1e-300)
            return text + f"; slowing the path down helps (by at least {factor:.3g}x: this step alone asks that)"
        return text + "; slowing the path down likely helps (accelerations' efforts fall with the speed squared)"

    def _binds(self) -> str:
        """What binds, without advice."""
        if self.kind == "singular":
            return "the hands cannot hold still at this posture even without limits (a singular posture)"
        if self.kind in ("floor", "constraint"):
            return f"{'the floor' if self.kind == 'floor' else 'a constraint'} binds: {self.joint}"
        if self.kind == "limits together":
            return "the velocity, position and effort limits together leave no motion"
        unit = self.unit or ("N m or N" if self.kind == "effort" else "rad/s or m/s")
        return (
            f"the {self.kind} limit of {self.joint} binds: the step asks {self.asked:.4g}, the limit allows "
            f"{self.allowed:.4g} ({unit})"
        )

    def to_dict(self) -> dict:
        return {**dataclasses.asdict(self), "message": self.message()}


def diagnose_step(
    robot: Robot,
    q: np.ndarray,
    h: float,
    effort_map: tuple[np.ndarray, np.ndarray],
    J_u: np.ndarray,
    b: np.ndarray,
    step: int,
    t: float,
) -> CarryDiagnosis:
    """Which limit makes the step's QP infeasible: each limit of each wheel and joint relaxed
    alone (position bounds widened to the velocity limits, a velocity limit lifted, an effort
    row dropped); the first whose relaxation alone makes the step feasible binds, and the
    relaxed solution says what the step asks of it.

    Args:
        robot, q: the robot and its configuration at the step, (nq,).
        h: the step's duration (s).
        effort_map: (A, offset), the step's efforts tau = A x + offset (:func:`_effort_map`).
        J_u, b: the step's tracking equality J_u x = b.
        step, t: the step's index and time (s), reported.
    """
    nx = robot.nx
    vel = np.asarray(robot.velocity_limits, dtype=float)
    effort = np.asarray(robot.effort_limits, dtype=float)
    lo, hi = velocity_bounds(robot, q, h)
    A, offset = effort_map
    H = np.diag(1.0 / vel**2)
    c = np.zeros(nx)
    names = robot.reduced_velocity_names
    big = 1e6 * np.maximum(vel, 1.0)

    def solve(lo_, hi_, rows):
        bound = EFFORT_SHARE * effort[rows]
        G = np.vstack([A[rows], -A[rows]]) if len(rows) else None
        g = np.concatenate([bound - offset[rows], bound + offset[rows]]) if len(rows) else None
        return solve_step_qp(H, c, J_u, b, lo_, hi_, G, g)

    everything = np.arange(nx)

    def unit(k: int, kind: str) -> str:
        linear = _is_prismatic(robot, q, k)
        if kind == "effort":
            return "N" if linear else "N m"
        return "m/s" if linear else "rad/s"

    def position_and_limit(k: int, upper: bool) -> tuple[float | None, float | None]:
        return _joint_position_and_limit(robot, q, k, upper)

    alone = diagnose_alone(solve, names, lo, hi, vel, effort, (A, offset), position_and_limit, unit, step, t)
    if alone is not None:
        return alone
    # no single limit: each kind of limit lifted for every joint at once; the joint the relaxed
    # step asks the most of (relative to its limit) is named
    wide_lo, wide_hi = np.maximum(lo, -vel), np.minimum(hi, vel)
    position_free_lo, position_free_hi = -vel, vel
    x = solve(position_free_lo, position_free_hi, everything)
    if x is not None and (np.any(lo > -vel) or np.any(hi < vel)):
        over = np.maximum(x - hi, lo - x)
        k = int(np.argmax(over))
        allowed = hi[k] if x[k] > hi[k] else lo[k]
        position, limit = _joint_position_and_limit(robot, q, k, upper=x[k] > hi[k])
        return CarryDiagnosis(
            step, t, names[k], "position", float(x[k]), float(allowed), position, limit, False, unit(k, "position")
        )
    free_lo, free_hi = np.where(lo > -vel, lo, -big), np.where(hi < vel, hi, big)
    x = solve(free_lo, free_hi, everything)
    if x is not None:
        k = int(np.argmax(np.abs(x) / vel))
        allowed = float(np.copysign(vel[k], x[k]))
        return CarryDiagnosis(
            step, t, names[k], "velocity", float(x[k]), allowed, slowing_helps=True, unit=unit(k, "velocity")
        )
    x = solve(wide_lo, wide_hi, np.zeros(0, dtype=int))
    if x is not None:
        tau = A @ x + offset
        k = int(np.argmax(np.abs(tau) / effort))
        allowed = float(np.copysign(EFFORT_SHARE * effort[k], tau[k]))
        return CarryDiagnosis(
            step, t, names[k], "effort", float(tau[k]), allowed, slowing_helps=True, unit=unit(k, "effort")
        )
    return CarryDiagnosis(step, t, "", "limits together", slowing_helps=None)


def diagnose_alone(
    solve: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray | None],
    names: Sequence[str],
    lo: np.ndarray,
    hi: np.ndarray,
    vel: np.ndarray,
    effort: np.ndarray,
    effort_map: tuple[np.ndarray, np.ndarray],
    position_and_limit: Callable[[int, bool], tuple[float | None, float | None]],
    unit: Callable[[int, str], str],
    step: int,
    t: float,
) -> CarryDiagnosis | None:
    """The limit whose relaxation alone makes an infeasible step feasible (one robot's or a
    team's): ``"singular"`` where none at all would, then each position bound widened to its
    velocity limit, each velocity limit lifted and each effort row dropped, in that order;
    ``None`` where no single one does.

    Args:
        solve: the step's QP over velocity bounds (lower, upper), keeping the effort rows of the
            reduced velocities given; ``None`` where infeasible.
        names: each reduced velocity's name in the report.
        lo, hi: the step's velocity bounds (position limits included); vel: the velocity limits;
            effort: the effort limits, (nx,) each.
        effort_map: (A, offset) with the step's efforts A x + offset.
        position_and_limit: reduced velocity k's joint position and its upper (True) or lower
            limit.
        unit: reduced velocity k's unit of a ``"position"``, ``"velocity"`` or ``"effort"``.
        step, t: the step's index and time (s), reported.
    """
    A, offset = effort_map
    big = 1e6 * np.maximum(vel, 1.0)
    nx = len(names)
    everything = np.arange(nx)
    if solve(-big, big, np.zeros(0, dtype=int)) is None:
        return CarryDiagnosis(step, t, "", "singular", slowing_helps=False)
    for k in range(nx):
        # the position limit: the joint's bound narrower than its velocity limit
        if lo[k] > -vel[k] or hi[k] < vel[k]:
            lo_, hi_ = lo.copy(), hi.copy()
            lo_[k], hi_[k] = -vel[k], vel[k]
            x = solve(lo_, hi_, everything)
            if x is not None:
                allowed = hi[k] if x[k] > hi[k] else lo[k]
                position, limit = position_and_limit(k, x[k] > hi[k])
                return CarryDiagnosis(
                    step, t, names[k], "position", float(x[k]), float(allowed), position, limit, False,
                    unit(k, "position"),
                )  # fmt: skip
    for k in range(nx):
        lo_, hi_ = lo.copy(), hi.copy()
        lo_[k], hi_[k] = -big[k], big[k]
        x = solve(lo_, hi_, everything)
        if x is not None:
            allowed = vel[k] if x[k] > 0 else -vel[k]
            return CarryDiagnosis(
                step, t, names[k], "velocity", float(x[k]), float(allowed), slowing_helps=True, unit=unit(k, "velocity")
            )
    for k in range(nx):
        x = solve(lo, hi, np.delete(everything, k))
        if x is not None:
            tau = float(A[k] @ x + offset[k])
            allowed = float(np.copysign(EFFORT_SHARE * effort[k], tau))
            return CarryDiagnosis(step, t, names[k], "effort", tau, allowed, slowing_helps=True, unit=unit(k, "effort"))
    return None


def _is_prismatic(robot: Robot, q: np.ndarray, k: int) -> bool:
    """Whether reduced velocity k drives a prismatic joint (wheels are revolute)."""
    if k < robot.platform.n_reduced:
        return False
    model = robot.model
    v = int(np.flatnonzero(robot.null_space(q)[:, k])[0])
    joint = next(j for j in model.joints[1:] if j.idx_v <= v < j.idx_v + j.nv)
    return "P" in joint.shortname().replace("Planar", "")


def _joint_position_and_limit(robot: Robot, q: np.ndarray, k: int, upper: bool) -> tuple[float | None, float | None]:
    """The position of reduced velocity k's joint and its upper (or lower) limit; ``None`` for a wheel."""
    model = robot.model
    if k < robot.platform.n_reduced:
        return None, None
    v = int(np.flatnonzero(robot.null_space(q)[:, k])[0])
    joint = next(j for j in model.joints[1:] if j.idx_v <= v < j.idx_v + j.nv)
    limit = model.upperPositionLimit[joint.idx_q] if upper else model.lowerPositionLimit[joint.idx_q]
    return float(q[joint.idx_q]), float(limit)


def velocity_bounds(robot: Robot, q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounds (lower, upper) on the reduced velocities x over one step of ``dt`` (s), (nx,) each:
    the velocity limits, and each joint's position limit approached at most at (distance to the
    limit) / max(dt, :data:`LIMIT_HORIZON`)."""
    hi = np.array(robot.velocity_limits, dtype=float)
    lo = -hi
    model = robot.model
    horizon = max(dt, LIMIT_HORIZON)
    S = robot.null_space(q)
    n_eta = robot.platform.n_reduced
    for k in range(n_eta, robot.nx):
        v = int(np.flatnonzero(S[:, k])[0])
        joint = next(j for j in model.joints[1:] if j.idx_v <= v < j.idx_v + j.nv)
        if joint.nq != 1:
            continue
        qk = q[joint.idx_q]
        lower, upper = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
        if np.isfinite(lower):
            lo[k] = max(lo[k], min((lower - qk) / horizon, 0.0))
        if np.isfinite(upper):
            hi[k] = min(hi[k], max((upper - qk) / horizon, 0.0))
    return lo, hi


def solve_step_qp(H, c, A, b, lo, hi, G=None, h=None) -> np.ndarray | None:
    """min 1/2 x^T H x + c^T x subject to A x = b, lo <= x <= hi and G x <= h (DAQP through
    qpsolvers); ``None`` when it has no solution."""
    from qpsolvers import solve_qp

    return solve_qp(H, c, G=G, h=h, A=A, b=b, lb=lo, ub=hi, solver="daqp")


def effort_rows_of(effort_map: tuple[np.ndarray, np.ndarray], limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear inequalities G x <= h that keep the wheel and joint efforts of the step within
    their limits, from the step's effort map (A, offset) (:func:`_effort_map`): with
    xdot = (x - x_prev) / dt the efforts are affine in x, tau = A x + offset
    (:meth:`mobmanip.motion.MotionTerms.torques`, the velocity terms at x_prev), and
    -s tau_max <= tau <= s tau_max with s = :data:`EFFORT_SHARE`."""
    A, offset = effort_map
    bound = EFFORT_SHARE * limits
    return np.vstack([A, -A]), np.concatenate([bound - offset, bound + offset])


def _effort_map(robot, q, x_prev, dt, task, object_mass, gravity=None) -> tuple[np.ndarray, np.ndarray]:
    """(A, offset) with the step's efforts tau = A x + offset (see :func:`effort_rows_of`); on a ramp
    ``gravity`` is the floor's (:meth:`mobmanip.motion.carry_floor.CarryFloor.gravity`), default straight down."""
    from .in_motion import motion_terms

    terms = motion_terms(robot, q, x_prev, task, object_mass=object_mass, gravity=gravity)
    c = terms.torques(np.zeros(robot.nx))
    # d tau / d xdot = Q^-1 (P + J_u^T W^+ M_o (W^T)^+ J_u)
    inertia = terms.P + terms.J_u.T @ terms.W_pinv @ terms.M_o @ np.linalg.pinv(terms.W.T) @ terms.J_u
    A = np.linalg.solve(terms.Q, inertia) / dt
    return A, c - A @ x_prev
