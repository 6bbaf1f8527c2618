"""Faces of a 2-D or 3-D zonotope in one compiled pass (the hot path of small capacity polytopes).

The same combinatorial construction as :func:`mobmanip.sets.zonotope.low_dim_faces_numpy` (its
reference, written with NumPy), fused into one Numba routine so that a small zonotope -- an arm's
velocity or acceleration set, a handful of generators -- costs microseconds instead of the
hundreds of NumPy calls the reference makes:

1. zero generators are dropped and parallel ones merged (their signed sum);
2. in R^3 every pair of merged generators (g_i, g_j) gives the normal nu = g_i x g_j; the
   generators orthogonal to nu (the pair and any coplanar with it) span the facet, a 2-D
   zonotope shifted by c + sum_k sign(nu . g_k) g_k over the others; its vertices follow, in
   counter-clockwise order seen from +nu, from its generators sorted by angle in its plane.
   In R^2 each merged generator g_k is an edge, c + sum_l sign(nu . g_l) g_l +- g_k;
3. every vertex is a sign vector; equal sign vectors are one vertex, numbered in increasing
   order of their base-3 code (as ``numpy.unique`` would), so vertices are exact (c + G s).

The routine returns a status: 0 when the faces check out (Euler's formula and every facet's
support value, in R^3), otherwise the caller takes the general route, as with the reference.
"""

from __future__ import annotations

import math

import numpy as np

from ..support.compile_notice import first_call_notice, numba_cached, up_to

try:  # pragma: no cover - exercised when Numba is installed (the default)
    from numba import njit
except ImportError:  # pragma: no cover
    njit = None  # type: ignore[assignment]

#: Merged generators above this count do not fit a base-3 code in int64: the reference handles them.
MAX_MERGED = 39

_OK, _FAIL = 0, 1


def _empty_result(m, n):
    return (
        _FAIL,
        0,
        np.zeros((0, m)),
        np.zeros((0, n)),
        np.zeros((0, m)),
        np.zeros(0),
        np.zeros(0),
        np.zeros(1, dtype=np.int64),
        np.zeros(0, dtype=np.int64),
    )


def _merge(G):
    """Live generators merged by direction: (H (m, k), live (L,), group (L,), sigma (L,))."""
    m, n = G.shape
    norms = np.zeros(n)
    for j in range(n):
        acc = 0.0
        for i in range(m):
            acc += G[i, j] * G[i, j]
        norms[j] = math.sqrt(acc)
    scale = 0.0
    for j in range(n):
        if norms[j] > scale:
            scale = norms[j]
    count = 0
    live = np.empty(n, dtype=np.int64)
    for j in range(n):
        if norms[j] > 1e-12 * scale:
            live[count] = j
            count += 1
    live = live[:count]
    leader = np.empty(count, dtype=np.int64)
    sigma = np.empty(count)
    for a in range(count):
        ja = live[a]
        leader[a], sigma[a] = a, 1.0
        for b in range(count):
            jb = live[b]
            cos = 0.0
            for i in range(m):
                cos += (G[i, ja] / norms[ja]) * (G[i, jb] / norms[jb])
            if abs(cos) >= 1.0 - 1e-12:
                leader[a] = b
                sigma[a] = 1.0 if cos > 0.0 else (-1.0 if cos < 0.0 else 0.0)
                break
    is_leader = np.zeros(count, dtype=np.bool_)
    for a in range(count):
        is_leader[leader[a]] = True
    rank = np.empty(count, dtype=np.int64)
    k = 0
    for a in range(count):
        rank[a] = k
        if is_leader[a]:
            k += 1
    group = np.empty(count, dtype=np.int64)
    for a in range(count):
        group[a] = rank[leader[a]]
    H = np.zeros((m, k))
    for a in range(count):
        for i in range(m):
            H[i, group[a]] += G[i, live[a]] * sigma[a]
    return H, live, group, sigma, scale


def _vertices(center, flat, H, live, group, sigma, n):
    """Distinct sign vectors of ``flat`` (rows) in increasing code order: keys' points and ids."""
    rows, k = flat.shape
    m = H.shape[0]
    code = np.zeros(rows, dtype=np.int64)
    for r in range(rows):
        acc = 0
        p = 1
        for j in range(k):
            acc += int(flat[r, j] + 1.0) * p
            p *= 3
        code[r] = acc
    order = np.argsort(code, kind="mergesort")
    vid = np.empty(rows, dtype=np.int64)
    first = np.empty(rows, dtype=np.int64)
    count = 0
    for t in range(rows):
        r = order[t]
        if t == 0 or code[r] != code[order[t - 1]]:
            first[count] = r
            count += 1
        vid[r] = count - 1
    V = np.empty((count, m))
    Y = np.zeros((count, n))
    for v in range(count):
        r = first[v]
        for i in range(m):
            acc = 0.0
            for j in range(k):
                acc += flat[r, j] * H[i, j]
            V[v, i] = center[i] + acc
        for a in range(live.shape[0]):
            Y[v, live[a]] = flat[r, group[a]] * sigma[a]
    return V, Y, vid


def _widths(normals, H):
    f, k = normals.shape[0], H.shape[1]
    m = H.shape[0]
    out = np.zeros(f)
    for r in range(f):
        acc = 0.0
        for j in range(k):
            d = 0.0
            for i in range(m):
                d += normals[r, i] * H[i, j]
            acc += abs(d)
        out[r] = acc
    return out


def _faces_2d(center, G):
    m, n = G.shape
    H, live, group, sigma, scale = _merge(G)
    k = H.shape[1]
    if scale == 0.0 or k < 2 or k > MAX_MERGED:
        return _empty_result(m, n)
    nu = np.empty((k, 2))
    for a in range(k):
        length = math.sqrt(H[1, a] * H[1, a] + H[0, a] * H[0, a])
        if length <= 1e-12 * scale * scale:
            return _empty_result(m, n)
        nu[a, 0], nu[a, 1] = -H[1, a] / length, H[0, a] / length
    S = np.zeros((k, k))
    for a in range(k):
        for b in range(k):
            if b == a:
                continue
            d = nu[a, 0] * H[0, b] + nu[a, 1] * H[1, b]
            if abs(d) <= 1e-12 * math.sqrt(H[0, b] * H[0, b] + H[1, b] * H[1, b]):
                return _empty_result(m, n)  # (near-)parallel generators left unmerged
            S[a, b] = 1.0 if d > 0.0 else -1.0
    flat = np.empty((4 * k, k))  # [side, edge, end]: up edges s = S, then down edges s = -S
    for side in range(2):
        sgn = 1.0 if side == 0 else -1.0
        for a in range(k):
            for end in range(2):
                r = (side * k + a) * 2 + end
                for b in range(k):
                    flat[r, b] = sgn * S[a, b]
                flat[r, a] = (1.0 if end == 0 else -1.0) * sgn
    V, Y, vid = _vertices(center, flat, H, live, group, sigma, n)
    nv = V.shape[0]
    angle = np.empty(nv)
    for v in range(nv):
        angle[v] = math.atan2(V[v, 1] - center[1], V[v, 0] - center[0])
    order = np.argsort(angle)
    rank = np.empty(nv, dtype=np.int64)
    for t in range(nv):
        rank[order[t]] = t
    f = 2 * k
    ends = np.empty((f, 2), dtype=np.int64)
    for e in range(f):
        x, y = rank[vid[2 * e]], rank[vid[2 * e + 1]]
        if x > y:
            x, y = y, x
        if x == 0 and y == nv - 1:
            x, y = y, x
        ends[e, 0], ends[e, 1] = x, y
    pos = np.argsort(ends[:, 0].copy())
    normals = np.empty((f, 2))
    for e in range(f):
        src = pos[e]
        sgn = 1.0 if src < k else -1.0
        normals[e, 0], normals[e, 1] = sgn * nu[src % k, 0], sgn * nu[src % k, 1]
    offsets = np.empty(f)
    for e in range(f):
        offsets[e] = normals[e, 0] * center[0] + normals[e, 1] * center[1]
    widths = _widths(normals, H)
    ptr = np.arange(f + 1) * 2
    idx = np.empty(2 * f, dtype=np.int64)
    for e in range(f):
        idx[2 * e], idx[2 * e + 1] = ends[pos[e], 0], ends[pos[e], 1]
    return _OK, 2, V[order], Y[order], normals, offsets, widths, ptr, idx


def _faces_3d(center, G):
    m, n = G.shape
    H, live, group, sigma, scale = _merge(G)
    k = H.shape[1]
    if scale == 0.0 or k < 3 or k > MAX_MERGED:
        return _empty_result(m, n)
    npairs = k * (k - 1) // 2
    pi = np.empty(npairs, dtype=np.int64)
    pj = np.empty(npairs, dtype=np.int64)
    nu = np.empty((npairs, 3))
    p = 0
    for a in range(k):
        for b in range(a + 1, k):
            pi[p], pj[p] = a, b
            x = H[1, a] * H[2, b] - H[2, a] * H[1, b]
            y = H[2, a] * H[0, b] - H[0, a] * H[2, b]
            z = H[0, a] * H[1, b] - H[1, a] * H[0, b]
            length = math.sqrt(x * x + y * y + z * z)
            if length <= 1e-12 * scale * scale:
                return _empty_result(m, n)
            nu[p, 0], nu[p, 1], nu[p, 2] = x / length, y / length, z / length
            p += 1
    hnorm = np.empty(k)
    for b in range(k):
        hnorm[b] = math.sqrt(H[0, b] * H[0, b] + H[1, b] * H[1, b] + H[2, b] * H[2, b])
    dots = np.empty((npairs, k))
    member = np.zeros((npairs, k), dtype=np.bool_)
    coplanar = False
    for p in range(npairs):
        for b in range(k):
            d = nu[p, 0] * H[0, b] + nu[p, 1] * H[1, b] + nu[p, 2] * H[2, b]
            if b == pi[p] or b == pj[p]:
                dots[p, b] = 0.0
                member[p, b] = True
            else:
                dots[p, b] = d
                if abs(d) <= 1e-12 * hnorm[b]:
                    member[p, b] = True
                    coplanar = True
    # Facets: distinct member sets, in order of first appearance (one per pair without coplanarity).
    keep = np.ones(npairs, dtype=np.bool_)
    if coplanar:
        if k > 62:
            return _empty_result(m, n)
        codes = np.zeros(npairs, dtype=np.int64)
        for p in range(npairs):
            acc = 0
            for b in range(k):
                if member[p, b]:
                    acc |= np.int64(1) << b
            codes[p] = acc
        for p in range(npairs):
            for r in range(p):
                if keep[r] and codes[r] == codes[p]:
                    keep[p] = False
                    break
    facets = np.flatnonzero(keep)
    nf = facets.shape[0]
    sizes = np.empty(nf, dtype=np.int64)
    total = 0
    for t in range(nf):
        q = 0
        for b in range(k):
            if member[facets[t], b]:
                q += 1
        sizes[t] = 2 * q
        total += 2 * q
    flat = np.empty((2 * total, k))
    normals = np.empty((2 * nf, 3))
    ptr = np.zeros(2 * nf + 1, dtype=np.int64)
    row = 0
    for t in range(nf):
        p = facets[t]
        q = sizes[t] // 2
        M = np.empty(q, dtype=np.int64)
        c = 0
        for b in range(k):
            if member[p, b]:
                M[c] = b
                c += 1
        # generators sorted by angle in the facet's plane, each turned into [0, pi)
        turn = np.ones(q)
        ordered = np.empty(q, dtype=np.int64)
        if coplanar:
            h0 = H[:, M[0]]
            inv = 1.0 / math.sqrt(h0[0] * h0[0] + h0[1] * h0[1] + h0[2] * h0[2])
            e1 = h0 * inv
            e2 = np.array(
                [
                    nu[p, 1] * e1[2] - nu[p, 2] * e1[1],
                    nu[p, 2] * e1[0] - nu[p, 0] * e1[2],
                    nu[p, 0] * e1[1] - nu[p, 1] * e1[0],
                ]
            )
            ang = np.empty(q)
            for c in range(q):
                g = H[:, M[c]]
                a = e1[0] * g[0] + e1[1] * g[1] + e1[2] * g[2]
                b = e2[0] * g[0] + e2[1] * g[1] + e2[2] * g[2]
                if b < 0.0 or (b == 0.0 and a < 0.0):
                    turn[c] = -1.0
                ang[c] = math.atan2(b * turn[c], a * turn[c])
            ordered = np.argsort(ang, kind="mergesort")
        else:
            for c in range(q):
                ordered[c] = c
        rest = np.empty(k)
        for b in range(k):
            rest[b] = 0.0 if member[p, b] else (1.0 if dots[p, b] > 0.0 else (-1.0 if dots[p, b] < 0.0 else 0.0))
        # walk: all -1, then switched to +1 one by one, then back to -1 one by one
        up = row
        down = row + 2 * q
        for w in range(2 * q):
            for b in range(k):
                flat[up + w, b] = rest[b]
                flat[down + 2 * q - 1 - w, b] = -rest[b]
            for c in range(q):
                s = 1.0 if (w <= q and c < w) or (w > q and c >= w - q) else -1.0
                g = M[ordered[c]]
                flat[up + w, g] = s * turn[ordered[c]]
                flat[down + 2 * q - 1 - w, g] = s * turn[ordered[c]]
        row += 4 * q
        for i in range(3):
            normals[2 * t, i] = nu[p, i]
            normals[2 * t + 1, i] = -nu[p, i]
        ptr[2 * t + 1] = ptr[2 * t] + 2 * q
        ptr[2 * t + 2] = ptr[2 * t + 1] + 2 * q
    V, Y, vid = _vertices(center, flat, H, live, group, sigma, n)
    offsets = np.empty(2 * nf)
    for f in range(2 * nf):
        offsets[f] = normals[f, 0] * center[0] + normals[f, 1] * center[1] + normals[f, 2] * center[2]
    widths = _widths(normals, H)
    if coplanar:
        if V.shape[0] - total + 2 * nf != 2:  # Euler: V - E + F = 2 (E = half the face entries)
            return _empty_result(m, n)
        hsum = 0.0
        for i in range(3):
            for b in range(k):
                hsum += abs(H[i, b])
        for f in range(2 * nf):
            for e in range(ptr[f], ptr[f + 1]):
                v = vid[e]
                gap = normals[f, 0] * V[v, 0] + normals[f, 1] * V[v, 1] + normals[f, 2] * V[v, 2]
                if abs(gap - offsets[f] - widths[f]) > 1e-9 * max(hsum, 1e-300):
                    return _empty_result(m, n)
        return _OK, 0, V, Y, normals, offsets, widths, ptr, vid
    # In general position: the upper facets of every pair, then the lower ones (the reference's order).
    perm = np.empty(2 * nf, dtype=np.int64)
    for t in range(nf):
        perm[t], perm[nf + t] = 2 * t, 2 * t + 1
    idx = np.empty(4 * nf * 2, dtype=np.int64)
    for f in range(2 * nf):
        src = perm[f]
        for e in range(4):
            idx[4 * f + e] = vid[4 * src + e]
    return _OK, 4, V, Y, normals[perm], offsets[perm], widths[perm], np.arange(2 * nf + 1) * 4, idx


_compiled: dict = {}
#: Set dimensions whose kernel has been called in this process.
_CALLED: set[int] = set()
#: The most a compile of the kernel for 2-D and 3-D sets may take (s), printed.
_COMPILE_SECONDS = {2: up_to("faces 2-D"), 3: up_to("faces 3-D")}


def _compile():
    """Compile the kernels on first use (cached on disk by Numba between runs)."""
    global _empty_result, _merge, _vertices, _widths
    jit = njit(cache=True, nogil=True)
    _empty_result, _merge, _vertices, _widths = (jit(f) for f in (_empty_result, _merge, _vertices, _widths))
    _compiled[2], _compiled[3] = jit(_faces_2d), jit(_faces_3d)


def _kernels(m: int) -> list:
    """The compiled functions for m-D sets (compiled first if need be): what the disk cache must hold."""
    if not _compiled:
        _compile()
    return [_compiled[m], _empty_result, _merge, _vertices, _widths]


def kernel_cached(m: int) -> bool | None:
    """Whether Numba's disk cache holds the face kernel for ``m``-D sets (2 or 3): ``None`` where it
    cannot tell or Numba is missing (:func:`mobmanip.support.compile_notice.numba_cached`)."""
    if njit is None:  # pragma: no cover - Numba is a default dependency
        return None
    return numba_cached(_kernels(m))


def faces(center: np.ndarray, G: np.ndarray) -> dict | None:
    """Compiled faces of the zonotope center + G [-1, 1]^n in R^2 or R^3, or None.

    Args:
        center: (m,), m in {2, 3}.
        G: generators as columns, (m, n), finite.

    Returns:
        None (no Numba, or a zonotope the construction does not cover: flat, too many
        generators, inconsistent near-coplanarity), or the dict of
        :func:`mobmanip.sets.zonotope.low_dim_faces`.
    """
    m = G.shape[0]
    if njit is None or m not in (2, 3):  # pragma: no cover - Numba is a default dependency
        return None
    if not _compiled:
        _compile()
    what = f"the zonotope/polytope face kernel for {m}-D sets"
    with first_call_notice(_CALLED, m, what, _COMPILE_SECONDS[m], lambda: _kernels(m)):
        status, width, V, Y, normals, offsets, widths, ptr, idx = _compiled[m](
            np.ascontiguousarray(center, dtype=float), np.ascontiguousarray(G, dtype=float)
        )
    if status != _OK:
        return None
    if width:
        faces_list = list(idx.reshape(-1, width))
    else:
        bounds = ptr.tolist()
        faces_list = [idx[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    return {"vertices": V, "Y": Y, "normals": normals, "offsets": offsets, "widths": widths, "faces": faces_list}
