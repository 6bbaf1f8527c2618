"""Independent references for the capacity polytopes: linear programs written from the defining
equations, the closed chain's forward dynamics through Pinocchio, and the robots' terms.

Nothing here calls mobmanip's polytope code.
"""

from __future__ import annotations

import highspy
import numpy as np
import pinocchio as pin

import mobmanip

TASK_ROWS = {"planar": (0, 1), "planar_rigid": (0, 1, 5), "translational": (0, 1, 2), "spatial": (0, 1, 2, 3, 4, 5)}


def terms(robot, q, task, mass=None):
    """The analysis (exact path) and the arrays a polytope is built from."""
    an = mobmanip.analyze(robot, q, task, method="exact", object_mass=mass)
    obj = an.held_object
    return an, {
        "J_u": an.unified_jacobian,
        "W": an.grasp_matrix,
        "P": an.reduced_inertia,
        "Q": robot.Q,
        "xi": an.bias,
        "M_o": obj.inertia_matrix(task),
        "g_o": obj.gravity_vector(task),
        "effort_limits": robot.effort_limits,
        "velocity_limits": robot.velocity_limits,
    }


def dynamic_terms(t):
    return {k: t[k] for k in ("J_u", "W", "P", "Q", "xi", "M_o", "g_o", "effort_limits")}


class SupportLP:
    """max d . (selected columns) subject to row equalities and column bounds, on HiGHS, warm."""

    def __init__(self, A_eq, b_eq, lower, upper, objective_cols):
        A_eq = np.asarray(A_eq, dtype=float)
        self.h = highspy.Highs()
        self.h.silent()
        inf = highspy.kHighsInf
        lp = highspy.HighsLp()
        lp.num_row_, lp.num_col_ = A_eq.shape
        lp.col_cost_ = np.zeros(A_eq.shape[1])
        lp.col_lower_ = np.where(np.isinf(lower), -inf, lower)
        lp.col_upper_ = np.where(np.isinf(upper), inf, upper)
        lp.row_lower_ = lp.row_upper_ = np.asarray(b_eq, dtype=float)
        cols, rows = np.nonzero(A_eq.T)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = np.r_[0, np.cumsum(np.bincount(cols, minlength=A_eq.shape[1]))].astype(np.int32)
        lp.a_matrix_.index_ = rows.astype(np.int32)
        lp.a_matrix_.value_ = A_eq.T[cols, rows]
        lp.sense_ = highspy.ObjSense.kMaximize
        self.h.passModel(lp)
        self.cols = np.asarray(objective_cols, dtype=np.int32)

    def __call__(self, d) -> float:
        self.h.changeColsCost(len(self.cols), self.cols, np.asarray(d, dtype=float))
        self.h.run()
        assert self.h.getModelStatus() == highspy.HighsModelStatus.kOptimal
        return self.h.getInfo().objective_function_value


def kinematic_lp(J, W, vlim):
    """Columns (x, v_o): J x - W^T v_o = 0, |x| <= xdot_max."""
    mk, n = J.shape
    m = W.shape[0]
    A = np.hstack([J, -W.T])
    lo = np.r_[-vlim, np.full(m, -np.inf)]
    return SupportLP(A, np.zeros(mk), lo, -lo, np.arange(n, n + m))


def dynamic_lp(J, W, P, Q, xi, M_o, g_o, tau_max):
    """Columns (qdd, tau, h, a_o) with the three defining equations and |tau| <= tau_max."""
    mk, n = J.shape
    m = W.shape[0]
    A = np.zeros((n + mk + m, 2 * n + mk + m))
    b = np.zeros(n + mk + m)
    A[:n, :n], A[:n, n : 2 * n], A[:n, 2 * n : 2 * n + mk], b[:n] = P, -Q, J.T, xi  # P qdd - Q tau + J^T h = xi
    A[n : n + mk, :n], A[n : n + mk, 2 * n + mk :] = J, -W.T  # J qdd = W^T a
    A[n + mk :, 2 * n : 2 * n + mk], A[n + mk :, 2 * n + mk :], b[n + mk :] = W, -M_o, g_o  # W h = M_o a + g_o
    lo = np.r_[np.full(n, -np.inf), -tau_max, np.full(mk + m, -np.inf)]
    hi = np.r_[np.full(n, np.inf), tau_max, np.full(mk + m, np.inf)]
    return SupportLP(A, b, lo, hi, np.arange(2 * n + mk, 2 * n + mk + m))


def policy_map(J, W, P, Q, xi, M_o, g_o):
    """Lambda_o, mu_o of the minimum-norm policy (Eq. 33-35, corrected sign), from numpy's pinv."""
    J_pinv, W_pinv = np.linalg.pinv(J), np.linalg.pinv(W)
    Lam = np.linalg.solve(Q, P @ J_pinv @ W.T + J.T @ W_pinv @ M_o)
    mu = np.linalg.solve(Q, -xi + J.T @ W_pinv @ g_o)
    return Lam, mu


def min_norm_lp(J, W, P, Q, xi, M_o, g_o, tau_max):
    """Columns (a_o, tau): tau - Lambda_o a_o = mu_o, |tau| <= tau_max."""
    Lam, mu = policy_map(J, W, P, Q, xi, M_o, g_o)
    n, m = Lam.shape
    A = np.hstack([-Lam, np.eye(n)])
    lo = np.r_[np.full(m, -np.inf), -tau_max]
    return SupportLP(A, mu, lo, -lo, np.arange(m))


# ---------------------------------------------------------------------------------------------
# Pinocchio: what joint velocities and torques do to the hands and the held object.


def _actuation(robot) -> np.ndarray:
    """Generalized forces from reduced torques, by joint name (wheel and arm joints), (nv, nx)."""
    B = np.zeros((robot.model.nv, robot.nx))
    for k, name in enumerate(robot.reduced_velocity_names):
        B[robot.model.joints[robot.model.getJointId(name)].idx_v, k] = 1.0
    return B


def hand_velocities(robot, q, x, task) -> np.ndarray:
    """Stacked task velocities of the hands (LOCAL_WORLD_ALIGNED) for v = S x, from Pinocchio."""
    model, data = robot.model, robot.data
    pin.forwardKinematics(model, data, q, robot.S @ x)
    pin.updateFramePlacements(model, data)
    rows = list(TASK_ROWS[task])
    return np.concatenate(
        [pin.getFrameVelocity(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED).vector[rows] for arm in robot.arms]
    )


def closed_chain_acceleration(robot, q, task, tau, W, M_o, g_o) -> np.ndarray:
    """The object's acceleration at rest under reduced torques tau, by Pinocchio's ABA.

    Unknowns: the platform constraint forces A^T lambda (A spanning null(S^T)), the forces h the
    hands apply to the object (the object pushes back with -h at each tool frame, as external
    forces in ABA) and the object's acceleration a_o. Equations: A vdot = 0, the hands'
    accelerations equal W^T a_o, W h = M_o a_o + g_o. All are affine in the unknowns: their
    matrix comes from ABA at unit vectors with torques, gravity and load removed (no
    cancellation), the constant part from ABA at zero.
    """
    model, data = robot.model, robot.data
    nv, m, k = model.nv, W.shape[0], len(robot.arms)
    rows = list(TASK_ROWS[task])
    _, s, Vt = np.linalg.svd(robot.S.T)
    A = Vt[int(np.sum(s > 1e-12)) :]  # constraint directions, (nc, nv)
    nc = A.shape[0]
    B = _actuation(robot)
    zero_v = np.zeros(nv)

    def residual(z, linear=False):
        lam, h, a = z[:nc], z[nc : nc + m * k], z[nc + m * k :]
        torque, load = (np.zeros_like(tau), np.zeros_like(g_o)) if linear else (tau, g_o)
        fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            fext.append(pin.Force.Zero())
        pin.framesForwardKinematics(model, data, q)
        for i, arm in enumerate(robot.arms):
            wrench = np.zeros(6)
            wrench[rows] = -h[i * m : (i + 1) * m]  # what the object applies to the hand
            at_tool = pin.SE3(np.eye(3), data.oMf[arm.frame_id].translation)
            parent = model.frames[arm.frame_id].parentJoint
            fext[parent] = fext[parent] + data.oMi[parent].actInv(at_tool.act(pin.Force(wrench)))
        gravity = model.gravity.copy()
        if linear:
            model.gravity = pin.Motion.Zero()
        try:
            vdot = pin.aba(model, data, q, zero_v, B @ torque + A.T @ lam, fext).copy()
        finally:
            model.gravity = gravity
        pin.forwardKinematics(model, data, q, zero_v, vdot)
        pin.updateFramePlacements(model, data)
        acc = np.concatenate(
            [
                pin.getFrameClassicalAcceleration(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED).vector[rows]
                for arm in robot.arms
            ]
        )
        return np.concatenate([A @ vdot, acc - W.T @ a, W @ h - M_o @ a - load])

    size = nc + m * k + m
    r0 = residual(np.zeros(size))
    R = np.column_stack([residual(e, linear=True) for e in np.eye(size)])
    z = np.linalg.lstsq(R, -r0, rcond=None)[0]
    assert np.linalg.norm(R @ z + r0) <= 1e-9 * max(np.linalg.norm(r0), 1.0)
    return z[-m:]
