"""Planar capacity polytopes of many configurations in one compiled pass (the sweeps' hot path).

Row r is the polygon K_r = {a in R^2 : F_r a in c_r + G_r [-1, 1]^n} (F_r injective, (p, 2)),
either a zonotope (F = I, p = 2, its centre c) or a section of a zonotope whose centre the
caller gives (the origin for a velocity set, the least-squares point of F a = c for the
minimum-norm policy's set). For each row, as :class:`mobmanip.sets.polytope.Polytope` does one at a
time but without Qhull or NumPy calls:

1. the zonotope's facet normals nu in R^p, one per (p - 1)-subset of independent generators
   (the elimination of :func:`mobmanip.sets.zonotope.facet_normals`), pulled back to the plane:
   rows A = F^T nu / |F^T nu| with slacks s = (nu . c + sum_j |nu . g_j| - nu . F centre) / |F^T nu|,
   both signs (K = {a : A (a - centre) <= s});
2. the polygon from the rows by polarity, as :mod:`mobmanip.sets.hull` finds it: the points
   w_i = A_i / s_i in angular order, the farthest of each ray, then only those that turn left
   (the convex hull, counter-clockwise); each hull point is a facet of K, each hull edge (i, j)
   a vertex, the solution of A_i u = s_i, A_j u = s_j (a facet whose two vertices coincide to
   round-off is dropped);
3. the indices: area (the zonotope formula 4 sum_{i<j} |det(g_i, g_j)| for a zonotope, else the
   shoelace sum), inradius min_i s_i, circumradius max |u| over the vertices.

A row is declined (status 1; the caller computes it one at a time, the reference way) when its
generators nearly lose rank, a slack is not clearly positive, or the hull has fewer than three
points (where the reference asks Qhull): flat, empty or ill-conditioned sets stay on the
reference path.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..support.compile_notice import first_call_notice, numba_cached, up_to
from . import zonotope

try:  # pragma: no cover - exercised when Numba is installed (the default)
    from numba import njit
except ImportError:  # pragma: no cover
    njit = None  # type: ignore[assignment]

_OK, _DECLINED = 0, 1
#: A row whose generators' rank-revealing pivot (Gram-Schmidt with pivoting, twice orthogonalised,
#: i.e. QR of G^T with column pivoting) falls below this fraction of the first is declined. The
#: reference treats singular values below 1e-10 of the largest as flat; the last pivot over the
#: first exceeds sigma_min / sigma_max by at most 2^(p-1) sqrt(p), so the margin used is the
#: larger of this and 1e-9 2^(p-1) sqrt(p): every flat row is declined, with a factor 10 to spare.
_RANK_MARGIN = 1e-6
#: Slacks below this fraction of the largest are declined (a centre on or near the boundary).
_SLACK_MARGIN = 1e-9
#: Vertices closer than this fraction of the polygon's size are one (mobmanip.sets.hull.MERGE_RTOL).
_MERGE_RTOL = 1e-9


def _clearly_full_rank(Gr, work):  # pragma: no cover - compiled
    """Whether the rows of Gr (p, n) are independent with a margin: Gram-Schmidt with pivoting
    (the remaining row of largest residual first); its pivots are the diagonal of a rank-revealing
    QR of Gr^T. ``work`` is a (p, n) buffer."""
    p, n = Gr.shape
    margin = max(_RANK_MARGIN, 1e-9 * 2.0 ** (p - 1) * math.sqrt(p))
    for i in range(p):
        for j in range(n):
            work[i, j] = Gr[i, j]
    first = 0.0
    for k in range(p):
        best, bi = -1.0, k
        for i in range(k, p):
            acc = 0.0
            for j in range(n):
                acc += work[i, j] * work[i, j]
            if acc > best:
                best, bi = acc, i
        if bi != k:
            for j in range(n):
                work[k, j], work[bi, j] = work[bi, j], work[k, j]
        norm = math.sqrt(best)
        if k == 0:
            first = norm
        if not norm > margin * first:
            return False
        for j in range(n):
            work[k, j] /= norm
        for i in range(k + 1, p):
            for _ in range(2):  # twice: orthogonal to round-off
                dot = 0.0
                for j in range(n):
                    dot += work[i, j] * work[k, j]
                for j in range(n):
                    work[i, j] -= dot * work[k, j]
    return True


def _polygon_rows(
    F, c, G, centre, zonotope_rows, subsets, status, V, nv, facets, nf, area, inr, circ
):  # pragma: no cover - compiled
    """Fill the outputs of every row (see the module docstring); arrays are per row except
    ``subsets`` ((S, p - 1) generator subsets) and the work buffers made here."""
    count, p, n = G.shape
    S = subsets.shape[0]
    normals = np.empty((S, p))
    rows = np.empty((2 * S, 2))
    slack = np.empty(2 * S)
    pts = np.empty((2 * S, 2))
    lengths = np.empty(S)
    angle = np.empty(2 * S)
    radius = np.empty(2 * S)
    order = np.empty(2 * S, dtype=np.int64)
    keep = np.empty(2 * S, dtype=np.int64)
    ray = np.empty(2 * S, dtype=np.int64)
    left = np.empty(2 * S, dtype=np.bool_)
    U = np.empty((2 * S, 2))
    Gr = np.empty((p, n))
    work = np.empty((p, n))
    for r in range(count):
        status[r] = _DECLINED
        nv[r] = 0
        nf[r] = 0
        for i in range(p):
            for j in range(n):
                Gr[i, j] = G[r, i, j]
        # G must span R^p clearly (else the reference's equalities: a flat set)
        if n < p:
            continue
        if not _full_rank(Gr, work):
            continue
        _normals(Gr, subsets, normals)
        k = 0
        longest = 0.0
        for s in range(S):
            a0 = 0.0
            a1 = 0.0
            b = 0.0
            h = 0.0
            for i in range(p):
                a0 += F[r, i, 0] * normals[s, i]
                a1 += F[r, i, 1] * normals[s, i]
                b += normals[s, i] * (c[r, i] - F[r, i, 0] * centre[r, 0] - F[r, i, 1] * centre[r, 1])
            for j in range(n):
                d = 0.0
                for i in range(p):
                    d += normals[s, i] * Gr[i, j]
                h += abs(d)
            length = math.sqrt(a0 * a0 + a1 * a1)
            if length == 0.0:
                continue
            rows[k, 0], rows[k, 1], slack[k] = a0 / length, a1 / length, (b + h) / length
            rows[k + 1, 0], rows[k + 1, 1], slack[k + 1] = -a0 / length, -a1 / length, (h - b) / length
            lengths[k // 2] = length
            k += 2
            if length > longest:
                longest = length
        # drop rows whose pulled-back normal nearly vanishes (parallel to the whole set)
        kept = 0
        for i in range(0, k, 2):
            if lengths[i // 2] > 1e-12 * longest:
                for t in range(2):
                    rows[kept + t, 0], rows[kept + t, 1], slack[kept + t] = rows[i + t, 0], rows[i + t, 1], slack[i + t]
                kept += 2
        k = kept
        if k < 4:  # a parallelogram has two pairs of facets
            continue
        smax, smin = 0.0, np.inf
        for i in range(k):
            smax = max(smax, slack[i])
            smin = min(smin, slack[i])
        if not smin > _SLACK_MARGIN * smax:
            continue
        # The polygon from its polar points w_i = A_i / s_i, as mobmanip.sets.hull does it:
        # in angular order, one point per ray (the farthest), then left turns only.
        for i in range(k):
            pts[i, 0] = rows[i, 0] / slack[i]
            pts[i, 1] = rows[i, 1] / slack[i]
            angle[i] = math.atan2(pts[i, 1], pts[i, 0])
            radius[i] = math.hypot(pts[i, 0], pts[i, 1])
        order[:k] = np.argsort(angle[:k])
        rays = 0
        for t in range(k):
            if t > 0 and angle[order[t]] - angle[order[t - 1]] > 1e-12:
                rays += 1
            ray[t] = rays
        if angle[order[0]] + 2.0 * math.pi - angle[order[k - 1]] <= 1e-12:  # a ray along the cut at +-pi
            for t in range(k):
                if ray[t] == rays:
                    ray[t] = 0
            rays -= 1 if rays > 0 else 0
        m = rays + 1  # kept points, the farthest of each ray, in ray order
        for t in range(m):
            keep[t] = -1
        for t in range(k):
            i = order[t]
            if keep[ray[t]] < 0 or radius[i] > radius[keep[ray[t]]]:
                keep[ray[t]] = i
        scale = 0.0
        for t in range(k):
            scale = max(scale, radius[t])
        while m > 3:
            left_count = 0
            for t in range(m):
                i, prev, nxt = keep[t], keep[(t - 1) % m], keep[(t + 1) % m]
                ax, ay = pts[i, 0] - pts[prev, 0], pts[i, 1] - pts[prev, 1]
                bx, by = pts[nxt, 0] - pts[i, 0], pts[nxt, 1] - pts[i, 1]
                la, lb = math.hypot(ax, ay), math.hypot(bx, by)
                left[t] = ax * by - ay * bx > 1e-12 * la * lb + 1e-14 * scale * (la + lb)
                if left[t]:
                    left_count += 1
            if left_count == m:
                break
            j = 0
            for t in range(m):
                if left[t]:
                    keep[j] = keep[t]
                    j += 1
            m = j
        if m < 3:
            continue
        # facets t and t + 1 meet at U_t; a facet whose two vertices coincide is dropped
        while True:
            biggest = 0.0
            for t in range(m):
                i, j = keep[t], keep[(t + 1) % m]
                x, y, xa, ya = pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1]
                det = x * ya - y * xa
                U[t, 0], U[t, 1] = (ya - y) / det, (x - xa) / det
                biggest = max(biggest, abs(U[t, 0]), abs(U[t, 1]))
            short = -1
            for t in range(m):
                f = (t + 1) % m
                if max(abs(U[f, 0] - U[t, 0]), abs(U[f, 1] - U[t, 1])) <= _MERGE_RTOL * biggest:
                    short = t
                    break
            if short < 0 or m <= 3:
                break
            for t in range((short + 1) % m, m - 1):
                keep[t] = keep[t + 1]
            m -= 1
        far = 0.0
        for t in range(m):
            V[r, t, 0], V[r, t, 1] = centre[r, 0] + U[t, 0], centre[r, 1] + U[t, 1]
            far = max(far, math.sqrt(U[t, 0] * U[t, 0] + U[t, 1] * U[t, 1]))
            i = keep[t]
            facets[r, t, 0], facets[r, t, 1] = rows[i, 0], rows[i, 1]
            facets[r, t, 2] = rows[i, 0] * centre[r, 0] + rows[i, 1] * centre[r, 1] + slack[i]
        h_count = m
        if zonotope_rows[r]:
            total = 0.0
            for i in range(n):
                for j in range(i + 1, n):
                    total += abs(Gr[0, i] * Gr[1, j] - Gr[1, i] * Gr[0, j])
            area[r] = 4.0 * total
        else:
            total = 0.0
            for e in range(h_count):
                f = (e + 1) % h_count
                total += V[r, e, 0] * V[r, f, 1] - V[r, e, 1] * V[r, f, 0]
            area[r] = 0.5 * abs(total)
        inr[r] = max(smin, 0.0)
        circ[r] = far
        nv[r] = h_count
        nf[r] = h_count
        status[r] = _OK


def _supports(V, nv, D, out):  # pragma: no cover - compiled
    """max over the first nv[r] vertices of row r of D[r] . v."""
    for r in range(V.shape[0]):
        best = -np.inf
        for e in range(nv[r]):
            x = D[r, 0] * V[r, e, 0] + D[r, 1] * V[r, e, 1]
            if x > best:
                best = x
        out[r] = best


_compiled: dict[str, Any] = {}
_CALLED: set[str] = set()
#: The most a compile of the kernel may take (s), printed.
_COMPILE_SECONDS = up_to("planar sweep")


_normals = zonotope._normals_kernel
_full_rank = _clearly_full_rank


def _compile():
    """Compile the kernels on first use (cached on disk by Numba between runs)."""
    global _normals, _full_rank
    jit = njit(cache=True, nogil=True)
    _normals, _full_rank = jit(zonotope._normals_kernel), jit(_clearly_full_rank)
    _compiled["rows"] = jit(_polygon_rows)
    _compiled["supports"] = jit(_supports)


def _kernels() -> list:
    """The compiled functions (compiled first if need be): what the disk cache must hold."""
    if not _compiled:
        _compile()
    return [_compiled["rows"], _compiled["supports"], _normals, _full_rank]


def available() -> bool:
    """Whether the compiled kernel can run (Numba is installed)."""
    return njit is not None


def kernel_cached() -> bool | None:
    """Whether Numba's disk cache holds the kernel: ``None`` where it cannot tell or Numba is missing."""
    return None if njit is None else numba_cached(_kernels())


def facet_outputs(N: int, cap: int, width: int, size: str) -> dict[str, np.ndarray]:
    """The zeroed arrays a sweep kernel fills last, in its arguments' order: ``facets``
    (N, cap, width) and ``facet_count`` (N,), then ``size`` (the area or the volume),
    ``inradius`` and ``circumradius`` (N,)."""
    measures = {name: np.zeros(N) for name in (size, "inradius", "circumradius")}
    return {"facets": np.zeros((N, cap, width)), "facet_count": np.zeros(N, dtype=np.int64), **measures}


def polygons(F: np.ndarray, c: np.ndarray, G: np.ndarray, centre: np.ndarray, is_zonotope: np.ndarray) -> dict:
    """The polygons of every row, compiled.

    Args:
        F: maps (N, p, 2), injective.
        c: zonotope centres (N, p).
        G: generators (N, p, n), finite.
        centre: each set's centre (N, 2): c for a zonotope (F = I), the origin for c = 0.
        is_zonotope: (N,) bool, F = I (the area then comes from the generators).

    Returns:
        ``status`` (N,) (0: computed; 1: declined, see the module docstring), ``vertices``
        (N, v, 2) counter-clockwise and ``count`` (N,) of them, ``facets`` (N, v, 3) rows
        (a0, a1, b) with unit (a0, a1) and the facet a0 x + a1 y <= b (as many as vertices),
        ``area``, ``inradius`` and ``circumradius`` (N,).
    """
    if not _compiled:
        _compile()
    N, p, n = G.shape
    subsets = zonotope.combinations(n, p - 1)
    cap = 2 * len(subsets)
    out = {
        "status": np.ones(N, dtype=np.int64),
        "vertices": np.zeros((N, cap, 2)),
        "count": np.zeros(N, dtype=np.int64),
        **facet_outputs(N, cap, 3, "area"),
    }
    first = "rows" not in _CALLED
    with first_call_notice(_CALLED, "rows", "the planar polytope sweep kernel", _COMPILE_SECONDS, _kernels):
        _compiled["rows"](
            np.ascontiguousarray(F, dtype=float),
            np.ascontiguousarray(c, dtype=float),
            np.ascontiguousarray(G, dtype=float),
            np.ascontiguousarray(centre, dtype=float),
            np.ascontiguousarray(is_zonotope, dtype=np.bool_),
            subsets,
            *out.values(),
        )
        if first:  # compile the small query kernel inside the notice too
            supports(np.zeros((1, 1, 2)), np.zeros(1, dtype=np.int64), np.ones((1, 2)))
    return out


def supports(V: np.ndarray, count: np.ndarray, D: np.ndarray) -> np.ndarray:
    """max over row r's first count[r] vertices of D[r] . v, (N,) (-inf for a row without any)."""
    if not _compiled:
        _compile()
    out = np.empty(len(V))
    _compiled["supports"](V, count, np.ascontiguousarray(D, dtype=float), out)
    return out
