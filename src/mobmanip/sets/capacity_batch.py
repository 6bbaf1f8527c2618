"""Capacity polytopes of a sweep's chunk, stacked and compiled instead of one at a time.

:func:`mobmanip.sets.capacity.polytope_batch` builds one :class:`~mobmanip.sets.polytope.Polytope`
per configuration (about 0.4 ms each for the paper robot's planar sets). For a planar task
(m = 2) the kinematic polytope, the exact dynamic polytope and the minimum-norm policy's, and for
a 3-D task (translational, planar rigid) the exact dynamic polytope and a one-hand kinematic one
(the zonotopes), are built here for the whole chunk at once:

- kinematic: F = W^T, c = 0, G = J_u diag(xdot_max), stacked (a zonotope section centred at the
  origin; a plain zonotope with one hand, W = I);
- exact dynamic: the closed chain's null space N of C = [J_u, -W^T] (stacked SVDs), the
  inertia H = N_q^T P N_q + N_a^T M_o N_a (stacked Cholesky factors) and the zonotope
  c = N_a H^-1 (N_q^T xi - N_a^T g_o), G = N_a H^-1 N_q^T Q diag(tau_max), as
  :func:`mobmanip.sets.capacity.dynamic_polytope` builds it;
- minimum-norm policy (planar): F = Lambda_o, c = -mu_o, G = diag(tau_max) from stacked SVDs
  of J_u, as :func:`mobmanip.sets.capacity.min_norm_dynamic_polytope` builds it, for the rows
  whose centre is the origin or the least-squares point (no gravity in a horizontal task);

then :mod:`mobmanip.sets.polygon_kernel` gives every polygon's vertices, facets, area, inradius
and circumradius in one compiled pass (:mod:`mobmanip.sets.zonotope_batch_kernel` every 3-D
zonotope's facets, volume, inradius and circumradius), and :class:`CompiledPolytopeBatch`
answers the sweep's queries (support, widths, radius along, straight-line reach) from them.

Rows outside the generic case (a non-finite term, a grasp or closed chain that loses rank, a set
the kernel declines: flat or ill-conditioned) are computed one at a time by the reference path,
so they get the same sets, flags and errors as before. Minimum-norm sets whose centre is a
least-effort program (gravity in the task) or with blocked directions, 3-D sections (several
hands' kinematic sets, minimum-norm 3-D sets: a 3-D hull), 6-D tasks, and polytopes under
constraints beyond the joint boxes (the floor's contacts: linear programs,
:mod:`mobmanip.measures.polytopes`) keep the one-at-a-time path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import TaskError
from ..support.tolerances import RANK_RTOL
from . import polygon_kernel, zonotope_batch_kernel
from .polytope import Polytope

#: Kinds built here (the minimum-norm set for planar tasks only, where its centre is not a program).
FAST_KINDS = ("kinematic", "dynamic", "dynamic_min_norm")


class CompiledPolytopeBatch:
    """N capacity polytopes of one kind (2-D, or 3-D zonotopes), indices computed in one compiled pass.

    A :class:`mobmanip.sets.taskset.TaskSetBatch`: ``batch[n]`` is the reference
    :class:`Polytope` of row n (built on demand); ``volume``, ``isotropy``, ``support``,
    ``widths``, ``radius_along`` and :meth:`straight_line_reach` answer for every row at once.

    Args:
        F, c, G: the rows' maps (N, p, m), zonotope centres (N, p) and generators (N, p, n).
        centre: each set's centre (N, m), m = 2 or 3.
        is_zonotope: (N,) bool, F = I.
        generic: (N,) bool, rows the stacked construction covers; the others (and rows the
            kernel declines) come from ``reference``.
        reference: row index -> the reference path's polytope of that row.
    """

    def __init__(
        self,
        F: np.ndarray,
        c: np.ndarray,
        G: np.ndarray,
        centre: np.ndarray,
        is_zonotope: np.ndarray,
        generic: np.ndarray,
        reference: Callable[[int], Polytope],
    ) -> None:
        self._reference = reference
        self._count, self._dim = len(generic), centre.shape[1]
        self._F, self._c, self._G, self._centre = F, c, G, centre
        self._is_zonotope = np.asarray(is_zonotope, dtype=bool)
        m = self._dim
        if m == 2:
            rows = np.flatnonzero(generic)
            out = polygon_kernel.polygons(F[rows], c[rows], G[rows], centre[rows], self._is_zonotope[rows])
            out["volume"] = out["area"]
        else:  # 3-D: zonotopes only (a section's facets need a 3-D hull: the reference's Qhull)
            rows = np.flatnonzero(generic & self._is_zonotope)
            out = zonotope_batch_kernel.zonotopes(c[rows], G[rows])
            out["vertices"], out["count"] = np.zeros((len(rows), 0, m)), np.zeros(len(rows), dtype=np.int64)
        fast = np.zeros(self._count, dtype=bool)
        fast[rows[out["status"] == 0]] = True
        self._fast = fast
        self._V = np.zeros((self._count,) + out["vertices"].shape[1:])
        self._facets = np.zeros((self._count,) + out["facets"].shape[1:])
        self._nv = np.zeros(self._count, dtype=np.int64)
        self._nf = np.zeros(self._count, dtype=np.int64)
        self._V[rows], self._nv[rows] = out["vertices"], out["count"]
        self._facets[rows], self._nf[rows] = out["facets"], out["facet_count"]
        volume, inr, circ = np.zeros(self._count), np.zeros(self._count), np.zeros(self._count)
        volume[rows], inr[rows], circ[rows] = out["volume"], out["inradius"], out["circumradius"]
        self._polytopes: dict[int, Polytope] = {i: reference(i) for i in np.flatnonzero(~fast).tolist()}
        self.empty = np.zeros(self._count, dtype=bool)
        self.degenerate = np.zeros(self._count, dtype=bool)
        self._volume = np.where(fast, volume, 0.0)
        self._isotropy = np.where(fast & (circ > 0.0), inr / np.where(circ > 0.0, circ, 1.0), 0.0)
        for i, p in self._polytopes.items():
            self.empty[i], self.degenerate[i] = p.empty, p.degenerate
            for name, values in (("volume", self._volume), ("isotropy", self._isotropy)):
                try:
                    values[i] = getattr(p, name)
                except TaskError:  # as PolytopeBatch: too many facets to enumerate its vertices
                    values[i] = np.nan
        self._widths: np.ndarray | None = None

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, index: int) -> Polytope:
        i = range(self._count)[index]
        if i not in self._polytopes:
            self._polytopes[i] = self._reference(i)
        return self._polytopes[i]

    @property
    def dim(self) -> int:
        """Task dimension m."""
        return self._dim

    @property
    def computed(self) -> np.ndarray:
        """Which rows the compiled pass computed, (N,) bool (the others: the reference path)."""
        return self._fast.copy()

    @property
    def volume(self) -> np.ndarray:
        """Volumes (areas in 2-D), (N,) (0 where empty or degenerate; NaN where unavailable, as
        :class:`~mobmanip.sets.capacity.PolytopeBatch`)."""
        return self._volume

    @property
    def isotropy(self) -> np.ndarray:
        """Inradius over circumradius from each set's centre, (N,) (0 where empty or degenerate)."""
        return self._isotropy

    def _rows(self, direction: ArrayLike) -> np.ndarray:
        d = np.asarray(direction, dtype=float)
        if d.ndim == 1:
            d = np.broadcast_to(d, (self._count, d.shape[0]))
        m = self._dim
        if d.shape != (self._count, m) or not np.all(np.isfinite(d)):
            raise TaskError(
                f"directions must be finite, ({m},) or ({self._count}, {m}), got shape {np.shape(direction)}"
            )
        return d

    def support(self, direction: ArrayLike) -> np.ndarray:
        """max over set n of d . a, (N,), for one direction (m,) or one per row (N, m); 0 where empty."""
        d = self._rows(direction)
        out = np.zeros(self._count)
        zono = self._fast & self._is_zonotope
        if zono.any():  # as Polytope.supports: d . c + sum_j |d . g_j|
            dz = d[zono]
            out[zono] = np.einsum("ni,ni->n", dz, self._c[zono]) + np.abs(
                np.einsum("ni,nij->nj", dz, self._G[zono])
            ).sum(axis=1)
        section = self._fast & ~self._is_zonotope
        if section.any():  # as Polytope.supports: the largest over the vertices
            out[section] = polygon_kernel.supports(self._V[section], self._nv[section], d[section])
        for i, p in self._polytopes.items():
            out[i] = p.support(d[i])
        return out

    def radius_along(self, direction: ArrayLike) -> np.ndarray:
        """How far set n reaches from its centre along the unit direction of d, (N,); 0 where empty."""
        d = self._rows(direction)
        norms = np.linalg.norm(d, axis=1)
        if np.any(norms == 0.0):
            raise TaskError("radius_along needs non-zero directions")
        u = d / norms[:, None]
        centres = self._centre.copy()
        for i in np.flatnonzero(~self._fast).tolist():
            centres[i] = self[i].center
        out = np.maximum(self.support(u) - np.einsum("ni,ni->n", u, centres), 0.0)
        return np.where(self.empty, 0.0, out)

    @property
    def widths(self) -> np.ndarray:
        """Extent along each task axis, support(e_k) + support(-e_k), (N, m) (0 where empty)."""
        if self._widths is None:
            out = np.zeros((self._count, self._dim))
            for k in range(self._dim):
                e = np.eye(self._dim)[k]
                out[:, k] = np.maximum(self.support(e) + self.support(-e), 0.0)
            self._widths = np.where(self.empty[:, None], 0.0, out)
        return self._widths

    def straight_line_reach(self, direction: ArrayLike) -> np.ndarray:
        """The largest s >= 0 with s d / ``|d|`` in set n, (N,): how far along d from rest (the origin)
        (0 where the origin's ray misses the set or it is empty). Computed rows intersect the ray
        with their facets; the others solve :meth:`Polytope.straight_line_reach`'s program."""
        d = self._rows(direction)
        norms = np.linalg.norm(d, axis=1)
        if np.any(norms == 0.0):
            raise TaskError("straight_line_reach needs non-zero directions")
        u = d / norms[:, None]
        out = np.zeros(self._count)
        rows = np.flatnonzero(self._fast)
        if len(rows):
            A, b = self._facets[rows, :, :-1], self._facets[rows, :, -1]
            live = np.arange(A.shape[1])[None, :] < self._nf[rows][:, None]
            au = np.einsum("nfi,ni->nf", A, u[rows])
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = b / au
            hi = np.where(live & (au > 0.0), ratio, np.inf).min(axis=1)
            lo = np.where(live & (au < 0.0), ratio, -np.inf).max(axis=1)
            blocked = (live & (au == 0.0) & (b < 0.0)).any(axis=1)
            ok = ~blocked & (hi >= np.maximum(lo, 0.0))
            out[rows] = np.where(ok, hi, 0.0)
        for i in np.flatnonzero(~self._fast).tolist():
            out[i] = self[i].straight_line_reach(u[i])
        return out


def _finite_rows(*arrays: np.ndarray) -> np.ndarray:
    ok = np.ones(len(arrays[0]), dtype=bool)
    for a in arrays:
        ok &= np.isfinite(a.reshape(len(a), -1)).all(axis=1)
    return ok


def _stack(value: Any, count: int, ndim: int) -> np.ndarray:
    """``value`` with a leading axis of ``count`` rows (broadcast when it has none)."""
    a = np.asarray(value, dtype=float)
    return a if a.ndim == ndim else np.broadcast_to(a, (count,) + a.shape)


def _grasp_rank_ok(W: np.ndarray) -> np.ndarray:
    """Rows whose grasp matrix has full row rank with a margin over the reference's check."""
    s = np.sqrt(np.maximum(np.linalg.eigvalsh(W @ np.swapaxes(W, 1, 2)), 0.0))
    return (W.shape[1] <= W.shape[2]) & (s[:, 0] > 1e-6 * np.maximum(s[:, -1], 1e-300))


def compiled_polytope_batch(
    kind: str, reference: Callable[[int], Polytope], **terms: Any
) -> CompiledPolytopeBatch | None:
    """The batch of ``kind`` for the stacked ``terms`` of :func:`mobmanip.sets.capacity.polytope_batch`,
    or None where this route does not apply (a task dimension other than 2 or 3, another kind, no
    Numba, a term with an unexpected shape): the caller then builds the polytopes one at a time.

    Args:
        kind: ``"kinematic"``, ``"dynamic"`` or ``"dynamic_min_norm"``.
        reference: row index -> the reference path's polytope (for the rows outside the generic case).
        **terms: as :func:`mobmanip.sets.capacity.polytope_batch`.
    """
    if kind not in FAST_KINDS or not (polygon_kernel.available() and zonotope_batch_kernel.available()):
        return None
    try:
        J_u = np.asarray(terms["J_u"], dtype=float)
        count, mk, nx = J_u.shape
        W = _stack(terms["W"], count, 3)
        m = W.shape[1]
        if m not in (2, 3) or W.shape[2] != mk:
            return None
        limit_name = "velocity_limits" if kind == "kinematic" else "effort_limits"
        limits = _stack(terms[limit_name], count, 2)
        if limits.shape[1:] != (nx,):
            return None
    except (KeyError, ValueError):
        return None
    if not (np.all(np.isfinite(limits)) and np.all(limits >= 0.0)):
        return None  # the reference path names the bad limit
    generic = _finite_rows(J_u, W) & _grasp_rank_ok(W)
    Wt = np.swapaxes(W, 1, 2)
    if kind == "kinematic":
        F = Wt
        is_zonotope = np.zeros(count, dtype=bool)
        if mk == m:  # one hand: a plain zonotope when W is the identity (else the reference's inverse)
            is_zonotope = (W == np.eye(m)).all(axis=(1, 2))
            generic &= is_zonotope
        c = np.zeros((count, mk))
        G = J_u * limits[:, None, :]
        centre = np.zeros((count, m))
        return CompiledPolytopeBatch(F, c, G, centre, is_zonotope, generic, reference)
    try:
        P = _stack(terms["P"], count, 3)
        Q = _stack(terms["Q"], count, 3)
        xi = _stack(terms["xi"], count, 2)
        M_o = _stack(terms["M_o"], count, 3)
        g_o = _stack(terms["g_o"], count, 2)
    except KeyError:
        return None
    if P.shape[1:] != (nx, nx) or Q.shape[1:] != (nx, nx) or xi.shape[1:] != (nx,) or M_o.shape[1:] != (m, m):
        return None
    if g_o.shape[1:] != (m,):
        return None
    generic &= _finite_rows(P, Q, xi, M_o, g_o)
    identity_q = (Q == np.eye(nx)).all(axis=(1, 2))
    if not identity_q.all():  # the reference checks Q's rank: keep rows with a clearly regular Q
        sq = np.linalg.svd(np.where(generic[:, None, None], Q, np.eye(nx)), compute_uv=False)
        generic &= identity_q | (sq[:, -1] > 1e-8 * sq[:, 0])
    if kind == "dynamic_min_norm":
        shared_w = np.ndim(terms["W"]) == 2
        return _min_norm(J_u, W, shared_w, P, Q, xi, M_o, g_o, limits, identity_q, generic, reference)
    c = np.zeros((count, m))
    G = np.zeros((count, m, nx))
    rows = np.flatnonzero(generic)
    if len(rows):
        # the closed chain C = [J_u, -W^T] and its null space (the reference's SVD, stacked)
        C = np.concatenate([J_u[rows], -Wt[rows]], axis=2)
        _, s, Vt = np.linalg.svd(C, full_matrices=True)
        top = np.maximum(s[:, 0], 1e-300)
        full = (s > RANK_RTOL * top[:, None]).sum(axis=1) == mk
        full &= s[:, -1] > 1e-8 * top  # a margin over the reference's rank test
        generic[rows[~full]] = False
        rows, Vt = rows[full], Vt[full]
        N = np.swapaxes(Vt[:, mk:, :], 1, 2)
        N_q, N_a = N[:, :nx], N[:, nx:]
        H = np.swapaxes(N_q, 1, 2) @ P[rows] @ N_q + np.swapaxes(N_a, 1, 2) @ M_o[rows] @ N_a
        H = 0.5 * (H + np.swapaxes(H, 1, 2))
        eig = np.linalg.eigvalsh(H)
        spd = eig[:, 0] > 1e-10 * np.maximum(eig[:, -1], 1e-300)
        generic[rows[~spd]] = False
        rows, N_q, N_a, H = rows[spd], N_q[spd], N_a[spd], H[spd]
        L = np.linalg.cholesky(H)
        eye = np.broadcast_to(np.eye(H.shape[1]), H.shape)
        Linv = np.linalg.solve(L, eye)
        K = N_a @ (np.swapaxes(Linv, 1, 2) @ Linv)  # N_a H^-1
        rhs = np.einsum("nqd,nq->nd", N_q, xi[rows]) - np.einsum("nad,na->nd", N_a, g_o[rows])
        c[rows] = np.einsum("nad,nd->na", K, rhs)
        G[rows] = K @ (np.swapaxes(N_q, 1, 2) @ (Q[rows] * limits[rows][:, None, :]))
    F = np.broadcast_to(np.eye(m), (count, m, m))
    return CompiledPolytopeBatch(F, c, G, c.copy(), np.ones(count, dtype=bool), generic, reference)


def _min_norm(
    J_u, W, shared_w, P, Q, xi, M_o, g_o, limits, identity_q, generic, reference
) -> CompiledPolytopeBatch | None:
    """The minimum-norm policy's planar sets, {a : |Lambda_o a + mu_o| <= tau_max}, stacked as
    :func:`mobmanip.sets.capacity.min_norm_dynamic_polytope` builds them: F = Lambda_o, c = -mu_o,
    G = diag(tau_max). Rows where J_u loses rank (the end effectors cannot follow every object
    acceleration: blocked directions) or whose centre needs the least-effort program (c outside
    the range of F) are left to the reference."""
    count, mk, nx = J_u.shape
    m = W.shape[1]
    if m != 2:  # a 3-D section: the reference's Qhull
        return None
    U, s, Vt = np.linalg.svd(J_u, full_matrices=False)
    top = np.maximum(s[:, 0], 1e-300)
    generic &= ((s > RANK_RTOL * top[:, None]).sum(axis=1) == mk) & (s[:, -1] > 1e-8 * top)
    J_pinv = (np.swapaxes(Vt, 1, 2) / s[:, None, :]) @ np.swapaxes(U, 1, 2)
    # the reference's pinv(W), once when every row shares W
    W_pinv = np.broadcast_to(np.linalg.pinv(W[0]), (count, mk, m)) if shared_w else np.linalg.pinv(W)
    Wt = np.swapaxes(W, 1, 2)
    Jt = np.swapaxes(J_u, 1, 2)
    Lam = P @ (J_pinv @ Wt) + Jt @ (W_pinv @ M_o)
    mu = -xi + np.einsum("nxk,nk->nx", Jt, np.einsum("nkm,nm->nk", W_pinv, g_o))
    if not identity_q.all():
        Qs = np.where(generic[:, None, None], Q, np.eye(nx))
        Lam = np.linalg.solve(Qs, Lam)
        mu = np.linalg.solve(Qs, mu[:, :, None])[:, :, 0]
    with np.errstate(all="ignore"):
        Uf, sf, Vft = np.linalg.svd(np.where(generic[:, None, None], Lam, 0.0), full_matrices=False)
    generic &= sf[:, -1] > 1e-8 * np.maximum(sf[:, 0], 1e-300)  # F injective (the reference's check)
    c = -mu
    centre = np.zeros((count, m))
    offset = np.flatnonzero(generic & c.any(axis=1))
    if len(offset):  # as Polytope: the least-squares point when F a = c holds to 1e-12 of the set's size
        a = np.einsum(
            "nij,nj->ni",
            np.swapaxes(Vft[offset], 1, 2) / sf[offset][:, None, :],
            np.einsum("nki,nk->ni", Uf[offset], c[offset]),
        )
        residual = np.linalg.norm(np.einsum("nij,nj->ni", Lam[offset], a) - c[offset], axis=1)
        scale = np.maximum(np.linalg.norm(c[offset], axis=1), limits[offset].max(axis=1))
        consistent = residual <= 0.5e-12 * np.maximum(scale, 1e-300)  # half the reference's bound: no close calls
        centre[offset] = a
        generic[offset[~consistent]] = False
    G = limits[:, :, None] * np.eye(nx)  # diag(tau_max) per row
    return CompiledPolytopeBatch(Lam, c, G, centre, np.zeros(count, dtype=bool), generic, reference)


def warm_kernels(dim: int) -> None:
    """Compile (or load from Numba's disk cache) the kernel for ``dim``-dimensional sets now,
    announcing a compile: a sweep calls this before its progress bar and its worker processes."""
    if dim == 2 and polygon_kernel.available():
        F = np.broadcast_to(np.eye(2), (1, 2, 2))
        polygon_kernel.polygons(F, np.zeros((1, 2)), np.eye(2)[None], np.zeros((1, 2)), np.ones(1, dtype=bool))
    elif dim == 3 and zonotope_batch_kernel.available():
        zonotope_batch_kernel.zonotopes(np.zeros((1, 3)), np.eye(3)[None])
