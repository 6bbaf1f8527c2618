"""The SVD path: :mod:`mobmanip.sets.ellipsoid` stacked, for every row the fast paths do not certify.

It mirrors the reference path branch by branch with stacked SVDs and pseudo-inverses (null
spaces as masks over full SVD bases, so ranks may differ from row to row): rank-deficient or
ill-conditioned Jacobians (degenerate ellipsoids), dynamic ellipsoids at the edge of emptiness,
and rows whose estimated fast-path error exceeds the certificate threshold. :class:`SvdBacklog`
queues such rows over chunks, to compute them in one stacked call.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..support import tolerances as tol
from .results import EllipsoidBatch
from .setup import BatchSetup


def from_generators(center: np.ndarray, G: np.ndarray, empty: np.ndarray) -> EllipsoidBatch:
    """Stacked :meth:`Ellipsoid.from_generator`: centres (n, m), generators (n, m, d >= 1)."""
    n, m = center.shape
    U, s, _ = np.linalg.svd(G, full_matrices=True)
    semi = np.zeros((n, m))
    k = min(m, s.shape[1])
    semi[:, :k] = s[:, :k]
    scale = np.maximum(semi[:, 0], 1e-300)
    semi[semi <= tol.RANK_RTOL * scale[:, None]] = 0.0
    semi[empty] = 0.0
    positive = semi > 0.0
    inverse = np.where(positive, 1.0 / np.where(positive, semi, 1.0) ** 2, 0.0)
    matrix = (U * inverse[:, None, :]) @ np.swapaxes(U, 1, 2)
    return EllipsoidBatch(
        center=center,
        semi_axes=semi,
        axes=np.swapaxes(U, 1, 2).copy(),
        matrix=matrix,
        degenerate=np.any(~positive, axis=1),
        empty=np.asarray(empty, dtype=bool).copy(),
    )


def null_mask(A: np.ndarray, n_cols: int):
    """Stacked null spaces of A (n, r, n_cols): the full right basis (n, n_cols, n_cols) with the
    columns outside the null space zeroed, and the rank per row (as ellipsoids._null_space)."""
    _, s, vt = np.linalg.svd(A, full_matrices=True)
    scale = np.maximum(s[:, 0] if s.shape[1] else np.zeros(A.shape[0]), 1.0)
    rank = np.sum(s > tol.RANK_RTOL * scale[:, None], axis=1)
    mask = np.arange(n_cols)[None, :] >= rank[:, None]
    return np.swapaxes(vt, 1, 2) * mask[:, None, :], rank


def kinematic_svd(J_u: np.ndarray, W: np.ndarray, vlim: np.ndarray) -> EllipsoidBatch:
    """Stacked :func:`mobmanip.sets.ellipsoid.kinematic_ellipsoid` (both of its branches, row by row);
    W is (m, mk) or (n, m, mk)."""
    n, km, nx = J_u.shape
    m = W.shape[-2]
    J_hat = J_u * vlim
    U, s, _ = np.linalg.svd(J_hat, full_matrices=False)
    out = EllipsoidBatch.allocate(n, m)
    general = np.ones(n, dtype=bool)
    if s.shape[1] == km:
        full = s[:, -1] > tol.FAST_RTOL * s[:, 0]
        if full.any():
            B = ((W if W.ndim == 2 else W[full]) @ U[full]) / s[full][:, None, :]
            # A = B B^T; its eigenvectors come from the SVD of B, which keeps the large semi-axes
            # (small singular values of B) accurate where eigh(A) would square their conditioning.
            Ub, sb, _ = np.linalg.svd(B, full_matrices=False)
            ok = sb[:, -1] > 0.0
            rows = np.flatnonzero(full)[ok]
            out.semi_axes[rows] = 1.0 / sb[ok][:, ::-1]
            out.axes[rows] = np.swapaxes(Ub[ok][:, :, ::-1], 1, 2)
            out.matrix[rows] = (B @ np.swapaxes(B, 1, 2))[ok]
            general[rows] = False
    if general.any():
        Jg = J_hat[general]
        Wg = W if W.ndim == 2 else W[general]
        Wt = np.swapaxes(Wg, -1, -2)
        Wt_pinv = np.linalg.pinv(Wt)
        inconsistent = Jg - Wt @ (Wt_pinv @ Jg)
        N, _ = null_mask(inconsistent, nx)
        out.put_rows(general, from_generators(np.zeros((Jg.shape[0], m)), Wt_pinv @ Jg @ N, np.zeros(len(Jg), bool)))
    return out


def dynamic_svd(
    J_u: np.ndarray,
    W: np.ndarray,
    P: np.ndarray,
    Q_inv: np.ndarray | None,
    xi: np.ndarray,
    Mo: np.ndarray,
    g_o: np.ndarray,
    elim: np.ndarray,
    row_labels: np.ndarray,
) -> EllipsoidBatch:
    """Stacked :func:`mobmanip.sets.ellipsoid.dynamic_ellipsoid` (both of its branches, row by row);
    W is (m, mk) or (n, m, mk), M_o given by its diagonal (m,) or (n, m)."""
    n, km, nx = J_u.shape
    m = W.shape[-2]
    Z = 1.0 / elim
    U, s, Vt = np.linalg.svd(J_u, full_matrices=False)
    r = s.shape[1]
    out = EllipsoidBatch.allocate(n, m)
    general = np.ones(n, dtype=bool)

    def pick(A, rows):
        return A if A.ndim == 2 else A[rows]

    def lam_mu(rows, J_pinv, W_pinv):
        Jr, Wr = J_u[rows], pick(W, rows)
        Jt = np.swapaxes(Jr, 1, 2)
        M_o = (Mo if Mo.ndim == 1 else Mo[rows])[..., None, :] * np.eye(m)
        Lam = P[rows] @ (J_pinv @ np.swapaxes(Wr, -1, -2)) + Jt @ (W_pinv @ M_o)
        Wpg = W_pinv @ g_o
        mu = -xi[rows] + (np.einsum("nij,j->ni", Jt, Wpg) if Wpg.ndim == 1 else np.einsum("nij,nj->ni", Jt, Wpg))
        if Q_inv is not None:
            Lam, mu = Q_inv @ Lam, mu @ Q_inv.T
        return Lam, Z * mu

    if r == km:
        full = np.flatnonzero(s[:, -1] > tol.FAST_RTOL * s[:, 0])
        if full.size:
            J_pinv = (np.swapaxes(Vt[full], 1, 2) / s[full][:, None, :]) @ np.swapaxes(U[full], 1, 2)
            Wf = pick(W, full)
            W_pinv = np.swapaxes(np.linalg.solve(Wf @ np.swapaxes(Wf, -1, -2), Wf), -1, -2)
            Lam, mu_bar = lam_mu(full, J_pinv, W_pinv)
            L = Z[:, None] * Lam
            UL, sL, VtL = np.linalg.svd(L, full_matrices=False)
            ok = sL[:, -1] > tol.FAST_RTOL * sL[:, 0]
            if ok.any():
                along = np.einsum("nij,ni->nj", UL[ok], mu_bar[ok])
                center = -np.einsum("nji,nj->ni", VtL[ok], along / sL[ok])
                mu2 = np.einsum("ni,ni->n", mu_bar[ok], mu_bar[ok])
                rho2 = 1.0 - np.maximum(mu2 - np.einsum("ni,ni->n", along, along), 0.0)
                nonempty = rho2 > 0.0
                rows = full[ok]
                out.center[rows] = center
                semi = np.sqrt(np.maximum(rho2, 0.0))[:, None] / sL[ok]
                out.semi_axes[rows] = np.where(nonempty[:, None], semi[:, ::-1], 0.0)
                out.axes[rows] = np.where(nonempty[:, None, None], VtL[ok][:, ::-1], np.eye(m))
                ratio = np.where(nonempty, (sL[ok] ** 2).T / np.where(nonempty, rho2, 1.0), 0.0).T
                out.matrix[rows] = (np.swapaxes(VtL[ok], 1, 2) * ratio[:, None, :]) @ VtL[ok]
                out.degenerate[rows] = ~nonempty
                out.empty[rows] = ~nonempty
                general[rows] = False
    rows = np.flatnonzero(general)
    if rows.size == 0:
        return out
    # Range of J and J^+ from one SVD with one rank decision (as the single path).
    Ug, sg, Vtg = U[rows], s[rows], Vt[rows]
    rank = np.sum(sg > tol.RANK_RTOL * np.maximum(sg[:, 0], 1e-300)[:, None], axis=1)
    keep = np.arange(r)[None, :] < rank[:, None]
    s_inv = np.where(keep, 1.0 / np.where(keep, sg, 1.0), 0.0)
    U_r = Ug * keep[:, None, :]
    J_pinv = (np.swapaxes(Vtg, 1, 2) * s_inv[:, None, :]) @ np.swapaxes(Ug, 1, 2)
    Wg = pick(W, rows)
    W_pinv = np.linalg.pinv(Wg)
    Wt = np.swapaxes(Wg, -1, -2)
    N, nrank = null_mask(Wt - U_r @ (np.swapaxes(U_r, 1, 2) @ Wt), m)
    d = m - nrank
    Lam, mu_bar = lam_mu(rows, J_pinv, W_pinv)
    L = Z[:, None] * (Lam @ N)
    UL, sL, VtL = np.linalg.svd(L, full_matrices=False)
    rL = sL.shape[1]
    dd = np.minimum(d, rL)
    valid = np.arange(rL)[None, :] < dd[:, None]
    has = dd > 0
    last = np.take_along_axis(sL, np.maximum(dd - 1, 0)[:, None], axis=1)[:, 0]
    massless = has & (last <= tol.RANK_RTOL * np.maximum(sL[:, 0], 1e-300))
    if massless.any():
        row = int(row_labels[rows[np.flatnonzero(massless)[0]]])
        raise ModelError(
            f"configuration row {row}: an object acceleration needs no joint torque: "
            "the model has moving links without mass or inertia"
        )
    along = np.where(valid, np.einsum("nij,ni->nj", UL, mu_bar), 0.0)
    mu2 = np.einsum("ni,ni->n", mu_bar, mu_bar)
    outside2 = np.maximum(mu2 - np.einsum("ni,ni->n", along, along), 0.0)
    sL_inv = np.where(valid, 1.0 / np.where(valid, sL, 1.0), 0.0)
    NV = N @ np.swapaxes(VtL, 1, 2)
    center = -np.einsum("nij,nj->ni", NV, along * sL_inv)
    rho2 = 1.0 - outside2
    empty = np.where(has, rho2 <= 0.0, np.sqrt(mu2) >= 1.0)
    center[~has] = 0.0
    G = NV * (np.sqrt(np.maximum(rho2, 0.0))[:, None] * sL_inv)[:, None, :]
    G[empty | ~has] = 0.0
    out.put_rows(rows, from_generators(center, G, empty))
    return out


def per_row(A: np.ndarray, count: int, ndim: int) -> np.ndarray:
    """``count`` rows of A: a per-row array (``ndim`` dimensions) as it is, a constant repeated."""
    return A if A.ndim == ndim else np.broadcast_to(A, (count, *A.shape))


def _same_limits(items: list[tuple]):
    """Concatenate consecutive queued items (tuples of per-row arrays, then their limits) that
    share limits; yields (per-row arrays..., limits)."""
    start = 0
    for end in range(1, len(items) + 1):
        if end == len(items) or not np.array_equal(items[end][-1], items[start][-1]):
            group = items[start:end]
            fields = zip(*(item[:-1] for item in group))
            yield (*(np.concatenate(f) for f in fields), group[0][-1])
            start = end


class SvdBacklog:
    """Rows of several chunks left to the SVD path, computed together by :meth:`flush`: the
    stacked SVD path costs about as much for one row as for fifty (NumPy's per-call overhead),
    and only a few rows per thousand need it."""

    def __init__(self, setup: BatchSetup):
        self.setup = setup
        self.kinematic: list[tuple] = []
        self.dynamic: list[tuple] = []

    def add_kinematic(self, rows: np.ndarray, J_u: np.ndarray, W: np.ndarray, vlim: np.ndarray) -> None:
        """Queue kinematic rows: output row numbers (n,), J_u (n, mk, nx), W (m, mk) or
        (n, m, mk), and the velocity limits (nx,) they share."""
        self.kinematic.append((rows, J_u, per_row(W, len(rows), 3), vlim))

    def add_dynamic(self, rows, J_u, W, P, xi, Mo, elim) -> None:
        """Queue dynamic rows: output row numbers (n,), J_u, W as for :meth:`add_kinematic`,
        P (n, nx, nx) (decoupled already if asked), xi (n, nx), M_o's diagonal (m,) or (n, m),
        and the effort limits (nx,) they share."""
        count = len(rows)
        self.dynamic.append((rows, J_u, per_row(W, count, 3), P, xi, per_row(Mo, count, 2), elim))

    def flush(self, kinematic: EllipsoidBatch | None, dynamic: EllipsoidBatch | None) -> None:
        """Compute the queued rows into ``kinematic`` / ``dynamic`` (one stacked call per run of
        items with the same limits) and empty the queue."""
        setup = self.setup
        for rows, J_u, W, vlim in _same_limits(self.kinematic):
            kinematic.put_rows(rows, kinematic_svd(J_u, W, vlim))
        for rows, J_u, W, P, xi, Mo, elim in _same_limits(self.dynamic):
            dynamic.put_rows(rows, dynamic_svd(J_u, W, P, setup.Q_inv, xi, Mo, setup.g_o, elim, rows))
        self.kinematic.clear()
        self.dynamic.clear()
