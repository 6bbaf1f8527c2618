"""The fast path stacked in NumPy: the closed forms, with their a-priori error certificates.

The same algorithm as the compiled kernel (:mod:`mobmanip.engine.kernel`), vectorised over a
chunk instead of compiled per row: the path ``analyze_batch`` takes when Numba is not
installed, and an independent implementation the kernel is tested against. See
:mod:`mobmanip.engine` for the algebra. Each function fills the rows it certifies and returns
the mask of the rows it leaves to the SVD path.
"""

from __future__ import annotations

import numpy as np

from ..support import tolerances as tol
from ..support.tolerances import EPS
from .results import EllipsoidBatch
from .setup import BatchSetup
from .stacked_linalg import fro, safe_inv, sym_eigh
from .terms import ChunkTerms


def _pick(mask: np.ndarray):
    """Index for the rows of a mask: everything (a cheap view) when all are set."""
    return Ellipsis if mask.all() else mask


def kinematic_fast(setup: BatchSetup, t: ChunkTerms, vlim: np.ndarray, out: EllipsoidBatch, rows: slice):
    """Kinematic ellipsoids of the rows it can certify; returns the mask of the other rows.

    With J_hat of full row rank, the object velocities are v_o = T J_hat z for the joint motions
    z whose end-effector velocities a rigid object can follow (C^T J_hat z = 0, C a basis of
    null(W)). The generator G = Z J_hat with Z = T - Y^T C^T, Y = (C^T G_k C)^-1 C^T G_k T^T,
    spans the same ellipsoid (G G^T is the Schur complement of C^T G_k C). G G^T is stationary in
    Y, so the conditioning of C^T G_k C enters only to second order.
    """
    Jh = t.J_u * vlim
    # The single path takes its full-rank branch when sigma_min(J_hat) > 1e-8 sigma_max(J_hat);
    # certify it with margin: kappa(J_hat) <= kappa(J) max(vlim) / min(vlim) < 1e6.
    kappa_J = np.sqrt(t.gram()[2])
    with np.errstate(invalid="ignore"):
        branch = kappa_J * (np.max(vlim) / np.min(vlim)) < tol.CONDITION_LIMIT
    if setup.k == 1:
        G = Jh
        hard = ~branch
        z_norm = 1.0
    else:
        Gk = Jh @ np.swapaxes(Jh, 1, 2)
        T = setup.T if t.T is None else t.T
        C = setup.C if t.C is None else t.C
        Tt, Ct = np.swapaxes(T, -1, -2), np.swapaxes(C, -1, -2)
        GC = Gk @ C
        KK = Ct @ GC  # C^T G_k C
        X = np.swapaxes(GC, 1, 2) @ Tt  # C^T G_k T^T
        KKi, _ = safe_inv(KK)
        Y = KKi @ X
        Z = T - np.swapaxes(Y, 1, 2) @ Ct
        G = Z @ Jh
        kk_norm, kki_norm = fro(KK), fro(KKi)
        kappa = kk_norm * kki_norm
        with np.errstate(divide="ignore", invalid="ignore"):
            second_order = kk_norm * (EPS * kappa * fro(Y)) ** 2
        hard = ~np.isfinite(kappa) | (kappa > tol.GRAM_CONDITION_LIMIT) | ~branch
        z_norm = fro(Z)
    B = G @ np.swapaxes(G, 1, 2)
    lam, V = sym_eigh(B)
    lmin, lmax = lam[:, 0], lam[:, -1]
    with np.errstate(invalid="ignore", divide="ignore"):
        err = 8.0 * EPS * (z_norm * fro(Jh) * fro(G) + fro(B))
        if setup.k > 1:
            err = err + second_order
        # error of the smallest semi-axis relative to the largest: err / (2 s_min s_max)
        est = err / (2.0 * np.sqrt(np.abs(lmin * lmax)))
        ok = (
            ~hard
            & (lmin * tol.GRAM_CONDITION_LIMIT > lmax)
            & (lmin > 0.0)
            & np.isfinite(est)
            & (est <= tol.FAST_PATH_TOLERANCE)
        )
    o, k = out.rows_view(rows), _pick(ok)
    lam_ok, V_ok = lam[k], V[k]
    o.semi_axes[k] = np.sqrt(lam_ok[:, ::-1])
    o.axes[k] = np.swapaxes(V_ok[:, :, ::-1], 1, 2)
    o.matrix[k] = (V_ok / lam_ok[:, None, :]) @ np.swapaxes(V_ok, 1, 2)
    o.center[k] = 0.0
    o.degenerate[k] = False
    o.empty[k] = False
    return ~ok


def dynamic_fast(
    setup: BatchSetup, t: ChunkTerms, P: np.ndarray, elim: np.ndarray, out: EllipsoidBatch, rows: slice
) -> np.ndarray:
    """Dynamic ellipsoids of the rows it can certify; returns the mask of the other rows.

    With J of full row rank, J^+ W^T = J^T (J J^T)^-1 W^T (one step of iterative refinement
    brings its error from eps kappa(J)^2 to about eps kappa(J)), so Lambda_o and mu_o follow
    from small products; the ellipsoid {a : ||L a + mu_bar|| <= 1} (L = Z Lambda_o) has centre
    c = -L^+ mu_bar (normal equations plus one refinement step), rho^2 = 1 - ||L c + mu_bar||^2
    and semi-axes sqrt(rho^2 / lambda_k) along the eigenvectors of L^T L, with lambda_k taken as
    the Rayleigh quotients ||L v_k||^2.
    """
    J_u = t.J_u
    Jt, solve, kappa = t.gram()  # kappa(J J^T): below GRAM_CONDITION_LIMIT the single path's full-rank branch
    T = setup.T if t.T is None else t.T
    Tt = np.swapaxes(T, -1, -2)  # W^+ = ((W^T)^+)^T for W of full row rank
    Wt = np.swapaxes(setup.W if t.W is None else t.W, -1, -2)
    JpWt = Jt @ solve(Wt)  # J^+ W^T, (n, nx, m)
    JpWt = JpWt + Jt @ solve(Wt - J_u @ JpWt)  # one step of refinement
    Mo = setup.Mo if t.Mo is None else t.Mo
    WpMo = Tt * (Mo[None, :] if Mo.ndim == 1 else Mo[:, None, :])
    Lam = P @ JpWt + Jt @ WpMo
    Wpg = Tt @ setup.g_o  # (km,) or (n, km)
    mu = -t.xi + (np.einsum("nij,j->ni", Jt, Wpg) if Wpg.ndim == 1 else np.einsum("nij,nj->ni", Jt, Wpg))
    if setup.Q_inv is not None:
        Lam = setup.Q_inv @ Lam
        mu = mu @ setup.Q_inv.T
    Z = 1.0 / elim
    L = Lam * Z[:, None]
    mub = mu * Z
    H = np.swapaxes(L, 1, 2) @ L
    lam, V = sym_eigh(H)
    LV = L @ V
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lam_rq = np.einsum("nij,nij->nj", LV, LV)  # Rayleigh quotients ||L v||^2
        Hinv = (V / lam_rq[:, None, :]) @ np.swapaxes(V, 1, 2)
        y = np.einsum("nij,ni->nj", L, mub)
        c = -np.einsum("nij,nj->ni", Hinv, y)
        r = mub + np.einsum("nij,nj->ni", L, c)
        c = c - np.einsum("nij,nj->ni", Hinv, np.einsum("nij,ni->nj", L, r))  # one refinement step
        r = mub + np.einsum("nij,nj->ni", L, c)
        outside2 = np.einsum("ni,ni->n", r, r)
        rho2 = 1.0 - outside2
        lmin, lmax = np.min(lam_rq, axis=1), np.max(lam_rq, axis=1)
        aniso = np.sqrt(lmax / lmin)
        mub2 = np.einsum("ni,ni->n", mub, mub)
        # error of L relative to its smallest singular value: the relative error of the
        # largest semi-axis; and what it does to rho^2 and to the centre
        err_l = 8.0 * EPS * (1.0 + np.sqrt(kappa) + EPS * kappa**2) * aniso
        err_rho2 = 2.0 * np.sqrt(outside2 * mub2) * err_l + 8.0 * EPS * mub2
        c_norm = np.sqrt(np.einsum("ni,ni->n", c, c))
        scale = np.maximum(np.sqrt(np.abs(rho2) / lmin), c_norm)
        err_c = err_l * (c_norm + np.sqrt(outside2 / lmin)) / scale
        ok = (
            np.isfinite(kappa)
            & (kappa < tol.GRAM_CONDITION_LIMIT)
            & (lmin > 0.0)
            & np.isfinite(aniso)
            & (aniso < tol.CONDITION_LIMIT)
            & (err_l <= tol.FAST_PATH_TOLERANCE)
            & (err_c <= tol.FAST_PATH_TOLERANCE)
            & (err_rho2 <= 2.0 * tol.FAST_PATH_TOLERANCE * np.abs(rho2))
        )
        empty = ok & (rho2 <= 0.0)
        full = ok & ~empty
        lam_sorted, V_sorted = lam_rq, V
        if not np.all(lam_rq[:, :-1] <= lam_rq[:, 1:]):  # Rayleigh quotients out of eigh's order
            order = np.argsort(lam_rq, axis=1)  # ascending eigenvalue = descending semi-axis
            lam_sorted = np.take_along_axis(lam_rq, order, axis=1)
            V_sorted = np.take_along_axis(V, order[:, None, :], axis=2)
    o, f = out.rows_view(rows), _pick(full)
    rho2_full = rho2[f]
    o.semi_axes[f] = np.sqrt(rho2_full[:, None] / lam_sorted[f])
    o.axes[f] = np.swapaxes(V_sorted[f], 1, 2)
    o.matrix[f] = H[f] / rho2_full[:, None, None]
    o.center[_pick(ok)] = c[_pick(ok)]
    o.degenerate[f] = False
    o.empty[f] = False
    if empty.any():
        o.semi_axes[empty] = 0.0
        o.axes[empty] = np.eye(setup.m)
        o.matrix[empty] = 0.0
        o.degenerate[empty] = True
        o.empty[empty] = True
    return ~ok
