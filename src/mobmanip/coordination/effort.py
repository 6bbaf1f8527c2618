"""The efforts of a team carrying its object, affine in the step's reduced velocities, and what
binds when a step of the team's QP has no solution.

Each robot's efforts follow the paper's policy for the whole team (as ``carry``'s do for one
robot, :meth:`mobmanip.motion.MotionTerms.torques`): with the team's stacked terms (J, P, Q and
the velocity-dependent bias xi at the previous step's rates, block-diagonal over the robots) and
one grasp matrix W over all hands,

    Q tau = P xdot - xi + J^T W^+ (M_o a_o + c_o + g_o),
    a_o = (W^T)^+ (J xdot + d/dt(J) x - Wdot^T v_o),

so the hands' wrenches on the object are W^+ (M_o a_o + c_o + g_o): the least-norm ones, with no
internal (squeezing) force; the robots are coupled only through the object's load. With
xdot = (x - x_prev) / dt, tau = A x + offset.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import scipy.linalg

from ..motion import grasp_matrix_rate, motion_terms
from ..motion.carry_step import EFFORT_SHARE, CarryDiagnosis, diagnose_alone, solve_step_qp
from ..robot.tasks import TaskSpace
from ..team import Team
from ..terms.grasp import HeldObject

__all__ = ["TeamStepMaps", "diagnose_team_step", "team_step_maps"]


class TeamStepMaps(NamedTuple):
    """A step's affine maps over the team's reduced velocities x (see :func:`team_step_maps`).

    Attributes:
        efforts: (A (nx, nx), offset (nx,)): tau = A x + offset.
        hand_wrenches: (F (m h, nx), f0 (m h,)): the wrenches the h hands apply to the object, on
            the task's m rows each (at the hand, world axes), F x + f0.
    """

    efforts: tuple[np.ndarray, np.ndarray]
    hand_wrenches: tuple[np.ndarray, np.ndarray]


def team_step_maps(
    team: Team,
    qs: Sequence[np.ndarray],
    x_prev: np.ndarray,
    dt: float,
    task: TaskSpace,
    held: HeldObject,
) -> TeamStepMaps:
    """The team's efforts and its hands' wrenches on the object over the step, affine in x (see
    the module's docstring): ``efforts`` (A, offset), tau = A x + offset, (nx, nx) and (nx,)
    (robots in order, each robot's wheels then joints).

    Args:
        team: the team; qs: each robot's configuration.
        x_prev: the team's reduced velocity over the previous step, (nx,).
        dt: the step (s); task: the team's task; held: the object as it is held now.
    """
    m = task.dim
    J, drift, P, Q, xi = [], [], [], [], []
    for member, q, s in zip(team.members, qs, team.member_slices()):
        robot = member.robot
        terms = motion_terms(robot, q, x_prev[s], task, object_mass=0.0, decoupled=team.decoupled)
        rows = np.concatenate([np.arange(a * m, (a + 1) * m) for a in member.arms])
        J.append(terms.J_u[rows])
        drift.append(terms.drift[rows])
        P.append(terms.P)
        Q.append(terms.Q)
        xi.append(terms.xi)
    J_u = scipy.linalg.block_diag(*J)
    P_t, Q_t = scipy.linalg.block_diag(*P), scipy.linalg.block_diag(*Q)
    W = held.grasp_matrix(task)
    W_pinv, Wt_pinv = np.linalg.pinv(W), np.linalg.pinv(W.T)
    M_o = held.inertia_matrix(task)
    v_o = Wt_pinv @ (J_u @ x_prev)
    omega = np.zeros(3)
    for i, r in enumerate(task.rows):
        if r >= 3:
            omega[r - 3] = v_o[i]
    grasp_drift = grasp_matrix_rate(task, np.cross(omega, held.offsets)).T @ v_o
    c_full = np.zeros(6)
    c_full[3:] = np.cross(omega, held.inertia @ omega)
    wrench = M_o @ (Wt_pinv @ (np.concatenate(drift) - grasp_drift)) + c_full[task.index] + held.gravity_vector(task)
    loads = W_pinv @ M_o @ Wt_pinv @ J_u  # the hands' wrenches per unit of xdot
    A = np.linalg.solve(Q_t, P_t + J_u.T @ loads) / dt
    base = np.linalg.solve(Q_t, -np.concatenate(xi) + J_u.T @ (W_pinv @ wrench))
    F = loads / dt
    return TeamStepMaps((A, base - A @ x_prev), (F, W_pinv @ wrench - F @ x_prev))


def effort_rows(A: np.ndarray, offset: np.ndarray, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """G x <= h keeping |A x + offset| within :data:`EFFORT_SHARE` of ``limits``."""
    bound = EFFORT_SHARE * limits
    return np.vstack([A, -A]), np.concatenate([bound - offset, bound + offset])


def diagnose_team_step(
    names: Sequence[str],
    units: Sequence[tuple[str, str]],
    H: np.ndarray,
    J_u: np.ndarray,
    b: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    velocity_limits: np.ndarray,
    A: np.ndarray,
    offset: np.ndarray,
    effort_limits: np.ndarray,
    positions: np.ndarray,
    position_limits: tuple[np.ndarray, np.ndarray],
    step: int,
    t: float,
) -> CarryDiagnosis:
    """Which limit makes a step of the team's QP infeasible, as ``carry``'s diagnosis does for one
    robot (:func:`mobmanip.motion.carry_step.diagnose_step`): with no limit at all (a singular
    posture), then each joint's position bound, velocity limit and effort row relaxed alone; the
    first relaxation that makes the step feasible names the joint (``"robot/joint"``).

    Args:
        names: ``"robot/joint"`` for each of the team's reduced velocities; units: their
            (velocity, effort) units.
        H, J_u, b: the step's QP weight and tracking equality.
        lo, hi: its velocity bounds (position limits included); velocity_limits: (nx,).
        A, offset, effort_limits: its effort map (:func:`team_step_maps`) and limits.
        positions, position_limits: each reduced velocity's joint position and its (lower,
            upper) limits (rad or m; NaN for a wheel), (nx,) each.
        step, t: the step's index and time (s).
    """
    nx = len(names)
    c = np.zeros(nx)

    def solve(lo_, hi_, keep):
        if not len(keep):
            return solve_step_qp(H, c, J_u, b, lo_, hi_)
        G, h = effort_rows(A[keep], offset[keep], effort_limits[keep])
        return solve_step_qp(H, c, J_u, b, lo_, hi_, G, h)

    def position_and_limit(k: int, upper: bool) -> tuple[float | None, float | None]:
        return float(positions[k]), float(position_limits[1][k] if upper else position_limits[0][k])

    def unit(k: int, kind: str) -> str:
        return units[k][1] if kind == "effort" else units[k][0]

    alone = diagnose_alone(
        solve, names, lo, hi, velocity_limits, effort_limits, (A, offset), position_and_limit, unit, step, t
    )
    if alone is not None:
        return alone
    return CarryDiagnosis(step, t, "", "limits together", slowing_helps=None)
