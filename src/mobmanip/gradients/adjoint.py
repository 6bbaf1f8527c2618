"""Reverse-mode (adjoint) gradients of the ellipsoids' measures, stacked over configurations.

The forward chain of :mod:`mobmanip.gradients` differentiates every intermediate matrix along
every tangent direction (arrays of nv matrices) and needs dJ/dq and dM/dq. Here the chain runs
backwards once from the measure: its sensitivity to the shape C and centre c, then to J_u, P,
xi, W and M_o, costs a few matrix products of the value's own sizes; only the last step, the
contraction with the configuration, visits the tangent directions, through the closed forms of
:mod:`mobmanip.gradients.tree_adjoint` (no kinematic Hessians, no dM/dq).

Reverse rules used (X_bar the sensitivity of f to X, all matrices stacked):
C = A^-1: A_bar = -C C_bar C; A = W K^-1 W^T: W_bar = (A_bar + A_bar^T) X^T, K_bar = -X A_bar X^T
with X = K^-1 W^T; K = J J^T: J_bar = (K_bar + K_bar^T) J; A^+ = A^T G, G = (A A^T)^-1:
A_bar = G (A^+)_bar^T + (K_bar + K_bar^T) A with K_bar = -G A (A^+)_bar G.
"""

from __future__ import annotations

import math

import numpy as np

from .rank import guarded, svd_full_rank
from .tree_adjoint import TreeAdjoint, TreePass, _first_call


def _T(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _sym(a: np.ndarray) -> np.ndarray:
    return a + _T(a)


def index_adjoint(objective, C: np.ndarray, c: np.ndarray | None):
    """An objective's values (n,) and its sensitivities to C (n, m, m) and to c (n, m) or ``None``.
    A block's objective (``objective.rows``) is that of the shadow on its rows: its sensitivities
    are those of the rows' sub-matrix, zero elsewhere."""
    if getattr(objective, "rows", None) is not None:
        r = np.asarray(objective.rows)
        value, sub_bar, sub_cbar = index_adjoint(objective.whole(), C[:, r][:, :, r], None if c is None else c[:, r])
        C_bar = np.zeros_like(C)
        C_bar[:, r[:, None], r[None, :]] = sub_bar
        c_bar = None
        if sub_cbar is not None and c is not None:
            c_bar = np.zeros_like(c)
            c_bar[:, r] = sub_cbar
        return value, C_bar, c_bar
    m = C.shape[-1]
    index = objective.index
    if index in ("log_volume", "log_isotropy"):
        _, logdet = np.linalg.slogdet(C)
        Ci = np.linalg.inv(C)
        if index == "log_volume":
            unit = 0.5 * m * math.log(math.pi) - math.lgamma(0.5 * m + 1.0)
            return unit + 0.5 * logdet, 0.5 * Ci, None
        trace = np.trace(C, axis1=1, axis2=2)
        return logdet / m - np.log(trace / m), Ci / m - np.eye(m) / trace[:, None, None], None
    if index == "capacity":
        d = np.asarray(objective.direction)
        spread = np.sqrt(np.maximum(np.einsum("i,nij,j->n", d, C, d), 1e-300))
        value = spread if c is None else c @ d + spread
        Cbar = np.outer(d, d)[None] / (2.0 * spread[:, None, None])
        return value, Cbar, np.broadcast_to(d, (C.shape[0], m))
    lam, U = np.linalg.eigh(C)
    u = U[:, :, 0]
    s = np.sqrt(np.maximum(lam[:, 0], 1e-300))
    return s, u[:, :, None] * u[:, None, :] / (2.0 * s[:, None, None]), None


def _pinv_rows(A: np.ndarray):
    """A^+ = A^T G and G = (A A^T)^-1 of full-row-rank stacked A."""
    G = np.linalg.inv(A @ _T(A))
    return _T(A) @ G, G


def _pinv_rows_adjoint(A, G, Ap_bar):
    """A_bar from (A^+)_bar for A^+ = A^T (A A^T)^-1."""
    K_bar = -G @ (A @ Ap_bar) @ G
    return G @ _T(Ap_bar) + _sym(K_bar) @ A


#: A row's rank is certified without an SVD where ||G||_F ||G^-1||_F of its Gram matrix G is
#: below this (then cond(A) < 1e6, far inside :data:`mobmanip.gradients.SINGULAR_RTOL`).
GRAM_CERTIFICATE = 1e12


def full_rank(A: np.ndarray) -> np.ndarray:
    """Per stacked matrix, whether all min(rows, cols) singular values exceed
    :data:`mobmanip.gradients.SINGULAR_RTOL` times the largest: certified from the condition of
    the smaller Gram matrix where that is clear, by an SVD of the remaining rows otherwise."""
    G = A @ _T(A) if A.shape[-2] <= A.shape[-1] else _T(A) @ A
    try:
        Gi = np.linalg.inv(G)
    except np.linalg.LinAlgError:
        return svd_full_rank(A)
    with np.errstate(invalid="ignore", over="ignore"):
        bound = np.sqrt(np.sum(G * G, axis=(1, 2)) * np.sum(Gi * Gi, axis=(1, 2)))
    ok = bound < GRAM_CERTIFICATE
    if not ok.all():
        unsure = ~ok
        ok[unsure] = svd_full_rank(A[unsure])
    return ok


def kinematic_adjoint(objective, J_u, W, velocity_limits, guard):
    """Value and sensitivities to J_u and W of a kinematic measure.

    Returns:
        (value (n,), J_u_bar (n, mk, nx), W_bar (n, m, mk)).
    """
    Jh = guard(J_u * velocity_limits)
    K = Jh @ _T(Jh)
    X = np.linalg.solve(K, _T(W))
    A = W @ X
    C = np.linalg.inv(A)
    C = 0.5 * (C + _T(C))
    value, Cbar, _ = index_adjoint(objective, C, None)
    A_bar = -C @ Cbar @ C
    W_bar = _sym(A_bar) @ _T(X)
    K_bar = -X @ A_bar @ _T(X)
    J_bar = (_sym(K_bar) @ Jh) * velocity_limits
    return value, J_bar, W_bar


def dynamic_adjoint(objective, J, P, xi, W, M_o, g_o, Qi, Z, guard, full_rank):
    """Value, definedness and sensitivities of a dynamic measure.

    Args:
        objective: the objective.
        J, P, xi: J_u (n, mk, nx), P (n, nx, nx), xi (n, nx).
        W, M_o: (n, m, mk), (n, m, m); g_o: (m,).
        Qi: Q^-1 (nx, nx) or ``None`` for the identity.
        Z: 1 / effort limits, (nx,).
        guard, full_rank: stand-in for rows not ``ok``, and the rank test of stacked matrices.

    Returns:
        (value, ok, bars) with bars a dict of sensitivities: ``J`` (n, mk, nx), ``Lam``
        (n, nx, m) of P B and ``B`` = J^+ W^T (so P_bar = Lam_bar B^T), ``xi`` (n, nx), ``W``,
        ``M_o``.
    """
    ok = full_rank(J)
    J = guard(J, ok)
    Jp, GJ = _pinv_rows(J)
    Wp, GW = _pinv_rows(W)
    B = Jp @ _T(W)  # (n, nx, m)
    E = Wp @ M_o  # (n, mk, m)
    Lam = P @ B + _T(J) @ E
    y = np.einsum("nij,j->ni", Wp, g_o)  # W^+ g_o, (n, mk)
    mu = -xi + np.einsum("nji,nj->ni", J, y)
    if Qi is not None:
        Lam, mu = Qi @ Lam, mu @ Qi.T
    L = Z[:, None] * Lam
    mb = Z * mu
    okL = full_rank(L)
    ok = ok & okL
    L = guard(L, okL)
    F = _T(L) @ L
    b = np.einsum("nij,ni->nj", L, mb)
    Fi = np.linalg.inv(F)
    Fi = 0.5 * (Fi + _T(Fi))
    c = -np.einsum("nij,nj->ni", Fi, b)
    rho2 = 1.0 - np.einsum("ni,ni->n", mb, mb) - np.einsum("ni,ni->n", b, c)
    ok &= rho2 > 1e-12
    C = guard(rho2[:, None, None] * Fi, ok)
    value, Cbar, cbar = index_adjoint(objective, C, c)
    # reverse
    rho2_bar = np.einsum("nij,nij->n", Cbar, Fi)
    Fi_bar = rho2[:, None, None] * Cbar
    mb_bar = -2.0 * rho2_bar[:, None] * mb
    b_bar = -rho2_bar[:, None] * c
    c_tot = -rho2_bar[:, None] * b if cbar is None else cbar - rho2_bar[:, None] * b
    Fi_bar = Fi_bar - c_tot[:, :, None] * b[:, None, :]
    b_bar = b_bar - np.einsum("nij,nj->ni", Fi, c_tot)
    F_bar = -Fi @ Fi_bar @ Fi
    L_bar = mb[:, :, None] * b_bar[:, None, :] + L @ _sym(F_bar)
    mb_bar = mb_bar + np.einsum("nij,nj->ni", L, b_bar)
    Lam_bar = Z[:, None] * L_bar
    mu_bar = Z * mb_bar
    if Qi is not None:
        Lam_bar, mu_bar = Qi.T @ Lam_bar, mu_bar @ Qi
    xi_bar = -mu_bar
    J_bar = y[:, :, None] * mu_bar[:, None, :] + E @ _T(Lam_bar)
    y_bar = np.einsum("nij,nj->ni", J, mu_bar)
    B_bar = _T(P) @ Lam_bar
    E_bar = J @ Lam_bar
    Wp_bar = y_bar[:, :, None] * g_o[None, None, :] + E_bar @ _T(M_o)
    M_o_bar = _T(Wp) @ E_bar
    Jp_bar = B_bar @ W
    W_bar = _T(B_bar) @ Jp + _pinv_rows_adjoint(W, GW, Wp_bar)
    J_bar = J_bar + _pinv_rows_adjoint(J, GJ, Jp_bar)
    return value, ok, {"J": J_bar, "Lam": Lam_bar, "B": B, "xi": xi_bar, "W": W_bar, "M_o": M_o_bar}


def grasp_position_adjoint(positions, W_bar, M_o_bar, mass, rows, linear_rows, angular_rows):
    """Sensitivity of the hands' positions (n, k, 3) from those of W and M_o, for the default
    object held between the hands (offsets r_i = p_i - mean(p), inertia 2/5 m max|r_i|^2).

    Args:
        positions: (n, k, 3).
        W_bar: (n, m, k m). M_o_bar: (n, m, m) or ``None``.
        mass: the object's mass (kg).
        rows: the task's rows of a 6-vector; linear_rows, angular_rows: indices into the task's
            m rows of its linear and angular entries.
    """
    n, k = positions.shape[:2]
    m = len(rows)
    offsets = positions - positions.mean(axis=1, keepdims=True)
    r_bar = np.zeros((n, k, 3))
    rows = list(rows)
    for i in range(k):
        K_bar = np.zeros((n, 3, 3))  # sensitivity of skew(r_i), in angular-by-linear full 3x3 coordinates
        block = W_bar[:, :, i * m : (i + 1) * m]
        for a_task in angular_rows:
            for l_task in linear_rows:
                K_bar[:, rows[a_task] - 3, rows[l_task]] = block[:, a_task, l_task]
        r_bar[:, i] = np.stack(
            [K_bar[:, 2, 1] - K_bar[:, 1, 2], K_bar[:, 0, 2] - K_bar[:, 2, 0], K_bar[:, 1, 0] - K_bar[:, 0, 1]], axis=1
        )
    if M_o_bar is not None and len(angular_rows):
        radius2 = np.einsum("nij,nij->ni", offsets, offsets)
        far = np.argmax(radius2, axis=1)
        take = np.arange(n)
        R2_bar = 0.4 * mass * sum(M_o_bar[:, a, a] for a in angular_rows)
        r_bar[take, far] += 2.0 * R2_bar[:, None] * offsets[take, far]
    return r_bar - r_bar.mean(axis=1, keepdims=True)


def kinematic_chunk_compiled(ev, tree: TreeAdjoint, qs: np.ndarray, passes: list | None = None):
    """:func:`gradient_chunk` for a kinematic objective through the compiled row loops of
    :mod:`mobmanip.gradients.tree_kernel` (the index's own adjoint stays in NumPy): the same values
    and gradients to round-off, each row computed on its own. ``None`` where a row's rank is not
    certified by the Gram bound (then the NumPy chain decides, with its SVD)."""
    if tree.k * ev.task.dim > ev.S.shape[1]:  # more task rows than reduced velocities: NumPy says undefined
        return None
    with _first_call("kinematic chain"):  # its four loops compile on a first call, announced once
        return _kinematic_chunk(ev, tree, qs, passes)


def _kinematic_chunk(ev, tree: TreeAdjoint, qs: np.ndarray, passes: list | None):
    kernel = tree.kernel
    assert kernel is not None
    t = tree.run_kinematic(qs)
    n, nv, k = qs.shape[0], tree.nv, tree.k
    task = ev.task
    rows, m = np.asarray(task.rows, dtype=np.int64), task.dim
    S, vlim = ev.S_contiguous, ev.velocity_limits
    # one argument type per loop (each further type is another compile and another cache load):
    # W read-only (a constant object's is cached read-only), the hands' positions contiguous
    W, _, _, moving = ev._object_terms(t.positions)
    W = np.ascontiguousarray(W)
    W.flags.writeable = False
    positions = np.ascontiguousarray(t.positions)
    Jh, X, C, bound = np.empty((n, k * m, S.shape[1])), np.empty((n, k * m, m)), np.empty((n, m, m)), np.empty(n)
    try:
        kernel.kinematic_shape(t.frames, rows, S, vlim, W, Jh, X, C, bound)
    except np.linalg.LinAlgError:
        return None
    if not np.all(bound < GRAM_CERTIFICATE):
        return None
    value, C_bar, _ = index_adjoint(ev.objective, C, None)
    J_bar6, W_bar = np.empty((n, k, 6, nv)), np.empty((n, m, k * m))
    kernel.kinematic_shape_adjoint(C, np.ascontiguousarray(C_bar), X, Jh, W, S, rows, vlim, k, J_bar6, W_bar)
    if moving:
        p_bar = grasp_position_adjoint(t.positions, W_bar, None, ev.mass, list(task.rows), task.linear_rows,
                                       task.angular_rows)  # fmt: skip
        p_bar = np.ascontiguousarray(p_bar)
    else:
        p_bar = np.zeros((n, k, 3))
    grad = np.empty((n, nv))
    kernel.frame_term(t.xi, positions, t.frames, tree.supports, tree.suffix, J_bar6, p_bar, grad)
    if passes is not None:
        passes.append(t)
    return np.asarray(value, dtype=float), grad, np.ones(n, dtype=bool)


def gradient_chunk(ev, tree: TreeAdjoint, qs: np.ndarray, passes: list | None = None):
    """(values, gradients (n, nv), defined) of a :class:`mobmanip.gradients.GradientEvaluator`'s
    objective at qs (n, nq), by the reverse chain; the chunk's :class:`TreePass` is appended to
    ``passes`` when given (its frames' poses and Jacobians, for callers that need them too). A
    kinematic objective runs the compiled row loops where Numba is available
    (:func:`kinematic_chunk_compiled`)."""
    if ev.objective.ellipsoid == "kinematic" and tree.kernel is not None:
        found = kinematic_chunk_compiled(ev, tree, qs, passes)
        if found is not None:
            return found
    t: TreePass = tree.run(qs, dynamics=ev.objective.ellipsoid == "dynamic")
    if passes is not None:
        passes.append(t)
    n, nv = qs.shape[0], tree.nv
    task, S = ev.task, ev.S
    rows = list(task.rows)
    ka, m = tree.k, task.dim
    J = t.frames[:, :, rows].reshape(n, ka * m, nv)
    J_u = J @ S
    W, M_o, g_o, moving = ev._object_terms(t.positions)
    if ev.objective.ellipsoid == "kinematic":
        if ka * m > J_u.shape[-1]:
            # K = Jh Jh^T is singular with fewer reduced velocities than the hands' task rows (a
            # 5-joint arm in a 6-D task): the ellipsoid is flat in the task, its index undefined
            return np.zeros(n), np.zeros((n, nv)), np.zeros(n, dtype=bool)
        Jh = J_u * ev.velocity_limits
        ok = full_rank(Jh)
        value, J_u_bar, W_bar = kinematic_adjoint(ev.objective, J_u, W, ev.velocity_limits, lambda A: guarded(A, ok))
        M_o_bar = None
        grad = np.zeros((n, nv))
    else:
        P = _T(S) @ t.M @ S
        ne = ev.robot.platform.n_reduced
        if ev.decoupled:
            P[:, :ne, ne:] = 0.0
            P[:, ne:, :ne] = 0.0
        assert t.g is not None  # a pass with dynamics computes gravity
        xi = -(t.g[:, None, :] @ S)[:, 0]  # row by row: a batch's rows equal one-row calls bit for bit
        Qi = None if ev.Q_identity else np.linalg.inv(ev.Q)
        value, ok, bars = dynamic_adjoint(ev.objective, J_u, P, xi, W, M_o, g_o, Qi, ev.Z, guarded, full_rank)
        J_u_bar, W_bar, M_o_bar = bars["J"], bars["W"], bars["M_o"]
        Lb, B = bars["Lam"], bars["B"]
        if ev.decoupled:  # P_bar = mask * (Lam_bar B^T): two pairs per column
            La, Ba = Lb.copy(), B.copy()
            La[:, :ne], Ba[:, :ne] = 0.0, 0.0
            Lb, B = Lb.copy(), B.copy()
            Lb[:, ne:], B[:, ne:] = 0.0, 0.0
            Lb, B = np.concatenate([Lb, La], axis=2), np.concatenate([B, Ba], axis=2)
        a_pairs = _T(S @ Lb)  # (n, R, nv)
        b_pairs = _T(S @ B)
        g_bar = -(bars["xi"][:, None, :] @ _T(S))[:, 0]
        grad = tree.bilinear_term(t, a_pairs, b_pairs, g_bar)
    J_bar6 = np.zeros((n, ka, 6, nv))
    J_bar6[:, :, rows] = (J_u_bar @ _T(S)).reshape(n, ka, m, nv)
    p_bar = None
    if moving:
        p_bar = grasp_position_adjoint(t.positions, W_bar, M_o_bar, ev.mass, rows, task.linear_rows, task.angular_rows)
    grad = grad + tree.frame_term(t, J_bar6, p_bar)
    value = np.where(ok, value, 0.0)
    grad[~ok] = 0.0
    return value, grad, ok
