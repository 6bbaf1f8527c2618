"""Facets, volume and farthest point of a zonotope {G y : y in [-1, 1]^n}, exactly.

A full-dimensional zonotope in R^r is bounded by the hyperplanes orthogonal to r - 1 linearly
independent generators: every facet normal is the generalised cross product of such a subset,
and the support value along a unit normal nu is ``sum_j |nu . g_j|``. Conversely every subset of
r - 1 independent generators gives a supporting halfspace (a facet when the generators are in
general position, a lower face otherwise), so the halfspaces from all subsets describe the
zonotope exactly, possibly with redundant rows.

The normals come from a small compiled kernel (Gaussian elimination with complete pivoting on
each subset, one solve per subset) when Numba is installed, else from cofactor determinants.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np

from ..errors import TaskError

#: Largest number of generator subsets enumerated for facets or volume; beyond it the count of
#: candidate facets makes the halfspace form impractical (e.g. 30 generators in 12 dimensions).
MAX_SUBSETS = 400_000
#: A subset whose eliminated pivot falls below this fraction of its largest entry is dependent.
_DEPENDENT_RTOL = 1e-12


@functools.cache
def _numba_njit():
    """Numba's ``njit``, imported at its first use (the import alone takes about 0.1 s, which a
    command that draws no polytope need not pay); ``None`` without Numba."""
    try:  # pragma: no cover - exercised when Numba is installed (the default)
        from numba import njit
    except ImportError:  # pragma: no cover
        return None
    return njit


def subset_count(n: int, k: int) -> int:
    """Number of k-subsets of n generators (0 when k > n)."""
    return math.comb(n, k) if 0 <= k <= n else 0


@functools.lru_cache(maxsize=64)
def combinations(n: int, k: int) -> np.ndarray:
    """All k-subsets of range(n) in lexicographic order, (C(n, k), k) int64 (read-only, cached)."""
    count = subset_count(n, k)
    if count > MAX_SUBSETS:
        raise TaskError(
            f"a zonotope with {n} generators in {k + 1} dimensions has {count} candidate facets "
            f"(more than {MAX_SUBSETS}); use support, contains, project or slice instead of its halfspaces"
        )
    flat = np.fromiter(itertools.chain.from_iterable(itertools.combinations(range(n), k)), dtype=np.int64)
    flat = flat.reshape(count, k)
    flat.setflags(write=False)
    return flat


def _normals_numpy(G: np.ndarray, subsets: np.ndarray) -> np.ndarray:
    """Generalised cross products from cofactors: nu_i = (-1)^i det(A without column i)."""
    r = G.shape[0]
    A = G.T[subsets]  # (s, r - 1, r): the subset's generators as rows
    out = np.empty((len(subsets), r))
    for i in range(r):
        cols = [k for k in range(r) if k != i]
        out[:, i] = (-1) ** i * np.linalg.det(A[:, :, cols])
    return out


def _normals_kernel(G, subsets, out):  # pragma: no cover - compiled
    r = G.shape[0]
    k = r - 1
    A = np.empty((k, r))
    perm = np.empty(r, dtype=np.int64)
    x = np.empty(r)
    for s in range(subsets.shape[0]):
        scale = 0.0
        for i in range(k):
            for c in range(r):
                v = G[c, subsets[s, i]]
                A[i, c] = v
                if abs(v) > scale:
                    scale = abs(v)
        for c in range(r):
            perm[c] = c
        dependent = scale == 0.0
        for step in range(k):
            if dependent:
                break
            # complete pivoting over the remaining block
            best, bi, bc = -1.0, step, step
            for i in range(step, k):
                for c in range(step, r):
                    v = abs(A[i, c])
                    if v > best:
                        best, bi, bc = v, i, c
            if best <= _DEPENDENT_RTOL * scale:
                dependent = True
                break
            if bi != step:
                for c in range(r):
                    A[step, c], A[bi, c] = A[bi, c], A[step, c]
            if bc != step:
                for i in range(k):
                    A[i, step], A[i, bc] = A[i, bc], A[i, step]
                perm[step], perm[bc] = perm[bc], perm[step]
            piv = A[step, step]
            for i in range(step + 1, k):
                f = A[i, step] / piv
                if f != 0.0:
                    for c in range(step, r):
                        A[i, c] -= f * A[step, c]
        if dependent:
            for c in range(r):
                out[s, c] = 0.0
            continue
        # Null vector in permuted coordinates: last one free (= 1), back substitution.
        x[k] = 1.0
        for i in range(k - 1, -1, -1):
            acc = A[i, k]
            for c in range(i + 1, k):
                acc += A[i, c] * x[c]
            x[i] = -acc / A[i, i]
        norm = 0.0
        for c in range(r):
            norm += x[c] * x[c]
        norm = math.sqrt(norm)
        for c in range(r):
            out[s, perm[c]] = x[c] / norm


_compiled = None


def facet_normals(G: np.ndarray) -> np.ndarray:
    """Unit normals, one per (r - 1)-subset of independent generators, deduplicated up to sign.

    Args:
        G: generators as columns, (r, n), spanning R^r (r >= 1).

    Returns:
        Unit normals ``nu`` (s, r), each with its sign chosen so that its largest entry is
        positive; the zonotope is ``{z : |nu . z| <= sum_j |nu . g_j|}`` for every row.
    """
    global _compiled
    r, n = G.shape
    if r == 1:
        return np.ones((1, 1))
    subsets = combinations(n, r - 1)
    G = np.ascontiguousarray(G, dtype=float)
    njit = _numba_njit()
    if njit is not None:
        if _compiled is None:
            _compiled = njit(cache=True, nogil=True)(_normals_kernel)
        normals = np.empty((len(subsets), r))
        _compiled(G, subsets, normals)
    else:  # pragma: no cover
        normals = _normals_numpy(G, subsets)
        lengths = np.linalg.norm(normals, axis=1)
        scale = np.prod(np.sort(np.linalg.norm(G, axis=0))[-(r - 1) :])
        keep = lengths > _DEPENDENT_RTOL * max(scale, 1e-300)
        normals = np.where(keep[:, None], normals / np.where(keep, lengths, 1.0)[:, None], 0.0)
    normals = normals[np.any(normals != 0.0, axis=1)]
    # One sign per normal (largest entry positive), then drop repeats (parallel generators).
    lead = normals[np.arange(len(normals)), np.argmax(np.abs(normals), axis=1)]
    normals = normals * np.sign(lead)[:, None]
    # Rows equal after rounding are one normal; keep each one's first occurrence, in order (a
    # lexicographic sort and a scan: ``numpy.unique`` over rows costs ~50 us on a few dozen rows).
    rounded = np.round(normals, 12) + 0.0  # + 0.0: -0.0 and 0.0 are one value
    order = np.lexsort(rounded.T[::-1])  # stable: within equal rows, increasing index
    ranked = rounded[order]
    new = np.empty(len(order), dtype=bool)
    new[:1] = True
    np.any(ranked[1:] != ranked[:-1], axis=1, out=new[1:])
    return normals[np.sort(order[new])]


def volume(G: np.ndarray) -> float:
    """Volume of the zonotope ``{G y : |y_i| <= 1}`` in R^m: ``2^m`` times the sum over m-subsets of ``|det G_S|``."""
    m, n = G.shape
    if n < m:
        return 0.0
    subsets = combinations(n, m)
    dets = np.linalg.det(G.T[subsets].transpose(0, 2, 1))
    return float(2.0**m * np.abs(dets).sum())


def max_norm(G: np.ndarray, limit: int = 20) -> float | None:
    """max over y in {-1, 1}^n of ||G y|| (the farthest point from the centre), or None when n > limit.

    The maximum of a convex function over the box is reached at a corner; the corners are
    enumerated in chunks (2^n of them).
    """
    m, n = G.shape
    if n > limit:
        return None
    best = 0.0
    half = min(n, 12)  # chunk: all signs of the first `half` generators, for each sign of the rest
    signs_a = (((np.arange(2**half)[:, None] >> np.arange(half)) & 1) * 2 - 1).astype(float)
    part_a = signs_a @ G[:, :half].T  # (2^half, m)
    rest = n - half
    signs_b = (((np.arange(2**rest)[:, None] >> np.arange(rest)) & 1) * 2 - 1).astype(float)
    part_b = signs_b @ G[:, half:].T if rest else np.zeros((1, m))
    for row in part_b:
        best = max(best, float(np.max(np.sum((part_a + row) ** 2, axis=1))))
    return math.sqrt(best)


def low_dim_faces(center: np.ndarray, G: np.ndarray) -> dict | None:
    """Vertices, faces and facets of a full-dimensional zonotope in R^2 or R^3, combinatorially.

    One compiled pass (:mod:`mobmanip.sets.zonotope_kernel`) when Numba is installed, else (or when
    the kernel declines) :func:`low_dim_faces_numpy`, the reference it is tested against; both
    give the same dict, described there.
    """
    from . import zonotope_kernel  # its compiler loads at the first face computed

    out = zonotope_kernel.faces(center, G)
    return out if out is not None else low_dim_faces_numpy(center, G)


def low_dim_faces_numpy(center: np.ndarray, G: np.ndarray) -> dict | None:
    """Vertices, faces and facets of a full-dimensional zonotope in R^2 or R^3, combinatorially.

    Parallel generators are merged first (their sum) and zero ones dropped. In R^3 the facets
    are then the parallelograms c + G s +- g_i +- g_j, s_k = sign(nu . g_k) for nu = g_i x g_j,
    when no three generators are coplanar; with coplanar generators (e.g. an arm with parallel
    joint axes) a facet is the polygon those generators span (:func:`_coplanar_faces`). In R^2
    the edges are c + G s +- g_k. None when the combinatorics do not check out (the caller then
    takes the general route). Vertices are identified by their sign vectors, so they
    are exact (c + G s) and come with their box coordinates.

    Returns:
        None, or a dict with ``vertices`` (v, m), ``Y`` (v, n) in {-1, 0, 1} (0 for zero
        generators), ``normals`` (f, m) unit outward, ``offsets`` (f,) = normal . c,
        ``widths`` (f,) = ``sum_j |normal . g_j|``, ``faces`` (list of index arrays, counter-clockwise
        seen from outside for m = 3, edges in boundary order for m = 2).
    """
    m, n = G.shape
    norms = np.linalg.norm(G, axis=0)
    scale = float(norms.max(initial=0.0))
    if m not in (2, 3) or scale == 0.0:
        return None
    live = np.flatnonzero(norms > 1e-12 * scale)
    unit = G[:, live] / norms[live]
    cos = unit.T @ unit
    parallel = np.abs(cos) >= 1.0 - 1e-12
    leader = np.argmax(parallel, axis=1)  # first generator parallel to each
    _, group = np.unique(leader, return_inverse=True)
    sigma = np.sign(cos[np.arange(len(live)), leader])  # y_k = sigma_k * (the merged generator's sign)
    H = np.zeros((m, group.max() + 1))
    np.add.at(H.T, group, (G[:, live] * sigma).T)
    k = H.shape[1]
    if k < m:
        return None
    if m == 2:
        nu = np.stack([-H[1], H[0]], axis=1)
        pairs = np.arange(k)[:, None]
    else:
        pairs = combinations(k, 2)
        nu = np.cross(H[:, pairs[:, 0]].T, H[:, pairs[:, 1]].T)
    length = np.linalg.norm(nu, axis=1)
    nu = nu / length[:, None]
    dots = nu @ H
    rows = np.arange(len(pairs))[:, None]
    dots[rows, pairs] = 0.0
    tiny = 1e-12 * np.linalg.norm(H, axis=0)
    hits = np.abs(dots) <= tiny
    hits[rows, pairs] = False
    if np.any(length <= 1e-12 * scale * scale):
        return None
    if hits.any():  # three or more coplanar generators (m = 3): polygonal facets
        return _coplanar_faces(center, H, nu, pairs, hits, n, live, group, sigma)
    S = np.sign(dots)  # (f, k), zero on the facet's own generators
    if m == 2:
        corners = np.array([[1.0], [-1.0]])
    else:  # counter-clockwise seen from +nu, nu = g_i x g_j
        corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    f, per = len(pairs), len(corners)
    signs = np.empty((2, f, per, k))
    for a, (side, order) in enumerate(((1.0, corners), (-1.0, corners[::-1]))):
        for b, corner in enumerate(order):
            s = side * S
            s[rows, pairs] = corner
            signs[a, :, b] = s
    flat = signs.reshape(-1, k)
    if k <= 39:  # a sign vector as one integer (base 3) makes the deduplication one-dimensional
        code = (flat + 1.0).astype(np.int64) @ (3 ** np.arange(k, dtype=np.int64))
        _, first, vid = np.unique(code, return_index=True, return_inverse=True)
        keys = flat[first]
    else:
        keys, vid = np.unique(flat, axis=0, return_inverse=True)
    vid = vid.ravel()
    vertices = center + keys @ H.T
    Y = np.zeros((len(keys), n))
    Y[:, live] = keys[:, group] * sigma
    face_ids = vid.reshape(2 * f, per)
    normals = np.vstack([nu, -nu])
    widths = np.concatenate([np.abs(nu @ H).sum(axis=1)] * 2)
    if m == 2:  # edges, in boundary order: sort vertices by angle
        order = np.argsort(np.arctan2(*(vertices - center).T[::-1]))
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        ends = np.sort(rank[face_ids], axis=1)
        wrap = (ends[:, 0] == 0) & (ends[:, 1] == len(order) - 1)
        ends[wrap] = ends[wrap][:, ::-1]
        pos = np.argsort(ends[:, 0])
        return {
            "vertices": vertices[order],
            "Y": Y[order],
            "normals": normals[pos],
            "offsets": normals[pos] @ center,
            "widths": widths[pos],
            "faces": list(ends[pos]),
        }
    return {
        "vertices": vertices,
        "Y": Y,
        "normals": normals,
        "offsets": normals @ center,
        "widths": widths,
        "faces": list(face_ids),
    }


def _coplanar_faces(center, H, nu, pairs, hits, n, live, group, sigma) -> dict | None:
    """Facets of a 3-D zonotope some of whose (merged) generators are coplanar.

    Each facet is orthogonal to the cross product nu of a pair of generators; its generators are
    all those orthogonal to nu (``hits`` and the pair), and it is the 2-D zonotope they span,
    shifted by c + sum_k sign(nu . h_k) h_k over the others. Its 2 q vertices, counter-clockwise
    seen from +nu, follow from the generators sorted by angle in the facet's plane (each turned
    into the half-plane [0, pi)): all at -1, then switched to +1 one by one, then back to -1.

    Returns:
        The dict of :func:`low_dim_faces`, or None when Euler's formula or the facets' support
        values do not check out (inconsistent near-coplanarity).
    """
    k = H.shape[1]
    members = hits.copy()
    rows = np.arange(len(pairs))
    members[rows, pairs[:, 0]] = members[rows, pairs[:, 1]] = True
    codes = members.astype(np.int64) @ (np.int64(1) << np.arange(k, dtype=np.int64)) if k <= 62 else None
    if codes is None:
        return None
    _, first = np.unique(codes, return_index=True)
    first = np.sort(first)
    facet_nu = nu[first]
    others = np.where(members[first], 0.0, np.sign(facet_nu @ H))  # (f, k)
    flat, sizes = [], []
    for r, nu_r, rest in zip(first, facet_nu, others):
        M = np.flatnonzero(members[r])
        h0 = H[:, M[0]]
        e1 = h0 / math.sqrt(h0 @ h0)
        e2 = np.array(
            [nu_r[1] * e1[2] - nu_r[2] * e1[1], nu_r[2] * e1[0] - nu_r[0] * e1[2], nu_r[0] * e1[1] - nu_r[1] * e1[0]]
        )
        a, b = e1 @ H[:, M], e2 @ H[:, M]
        turn = np.where((b < 0.0) | ((b == 0.0) & (a < 0.0)), -1.0, 1.0)
        order = np.argsort(np.arctan2(b * turn, a * turn), kind="stable")
        q = len(M)
        polygon = np.zeros((2 * q, k))
        polygon[:, M[order]] = _polygon_walk(q) * turn[order]
        up = polygon + rest
        down = polygon - rest
        flat += [up, down[::-1]]
        sizes += [2 * q, 2 * q]
    normals = np.empty((2 * len(first), 3))
    normals[0::2], normals[1::2] = facet_nu, -facet_nu
    flat = np.vstack(flat)
    code = (flat + 1.0).astype(np.int64) @ (3 ** np.arange(k, dtype=np.int64)) if k <= 39 else None
    if code is not None:
        _, first_vertex, vid = np.unique(code, return_index=True, return_inverse=True)
        keys = flat[first_vertex]
    else:
        keys, vid = np.unique(flat, axis=0, return_inverse=True)
    vid = vid.ravel()
    bounds = np.cumsum(sizes)
    faces = np.split(vid, bounds[:-1])
    vertices = center + keys @ H.T
    widths = np.abs(normals @ H).sum(axis=1)
    offsets = normals @ center
    if len(keys) - bounds[-1] // 2 + len(faces) != 2:  # Euler: V - E + F = 2
        return None
    owner = np.repeat(np.arange(len(faces)), sizes)
    gap = np.einsum("ij,ij->i", vertices[vid], normals[owner]) - (offsets + widths)[owner]
    if np.max(np.abs(gap)) > 1e-9 * max(float(np.abs(H).sum()), 1e-300):
        return None
    Y = np.zeros((len(keys), n))
    Y[:, live] = keys[:, group] * sigma
    return {"vertices": vertices, "Y": Y, "normals": normals, "offsets": offsets, "widths": widths, "faces": faces}


@functools.lru_cache(maxsize=32)
def _polygon_walk(q: int) -> np.ndarray:
    """Signs (2 q, q) of the vertices of a 2-D zonotope whose q generators are sorted by angle in
    [0, pi), counter-clockwise: all -1, then switched to +1 one by one, then back to -1."""
    steps = np.tril(np.ones((q, q)), -1)  # row i: the first i generators switched
    walk = np.vstack([2.0 * np.vstack([steps, np.ones((1, q))]) - 1.0, 1.0 - 2.0 * steps[1:]])
    walk.setflags(write=False)
    return walk
