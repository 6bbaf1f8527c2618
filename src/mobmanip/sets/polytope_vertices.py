"""Vertices of a capacity polytope K = {a : F a in c + G [-1, 1]^n}: their exact recovery from
the zonotope's faces, their enumeration above three dimensions, and the volume they enclose.

:class:`mobmanip.sets.polytope.Polytope` finds a low-dimensional set's vertices with one Qhull
call (:func:`mobmanip.sets.hull.enumerate_hull`), accurate to the conditioning of its facets;
:func:`exact_vertices` then recomputes each one, with the joint values that reach it, from the
face of the zonotope it lies on. Above three dimensions :func:`halfspace_vertices` intersects
the halfspaces in the set's own plane (for volume and isotropy only); :func:`distinct_rows`
keeps one row of each halfspace listed more than once. Functions of arrays: the polytope keeps the
caching and decides when each is called.
"""

from __future__ import annotations

import numpy as np

from ..errors import TaskError
from ..support.tolerances import RANK_RTOL
from .hull import _groups, enumerate_hull

#: Above 3 dimensions, vertices (for volume and isotropy) are enumerated only up to this many
#: halfspaces: beyond, Qhull's output explodes (a 6-D kinematic section of TIAGo++ has ~5,000).
MAX_HIGH_DIM_ROWS = 400
#: Two halfspace rows are one when, each divided by the length of its normal, their normals agree
#: to this in every coordinate and their offsets to this times the set's size.
DUPLICATE_RTOL = 1e-9


def distinct_rows(
    A: np.ndarray, offsets: np.ndarray, size: float, rtol: float = DUPLICATE_RTOL
) -> tuple[np.ndarray, np.ndarray]:
    """One row of each halfspace ``A_i a <= b_i`` that is listed more than once.

    The rule: every row (its normal and its offsets) is divided by the length of its normal, so a
    copy scaled by a positive factor becomes the same row; rows i and j are then one halfspace when
    ``max |A_i - A_j| <= rtol`` and ``max |b_i - b_j| <= rtol * size``. Of each such group (taken
    transitively) the first row is kept, in the original order. Opposite rows (an equality's two
    sides) differ in sign and stay. Removing a copy leaves the set as it was: only rows that agree
    to the tolerance are merged, and the row kept is one of them.

    Args:
        A: normals, (r, m); a zero normal is compared as it is (not divided).
        offsets: (r,), or (r, k) for several offsets per row (e.g. the parts of b that are scaled
            separately); all must agree.
        size: the set's size, the scale of the offsets' tolerance.
        rtol: the tolerance, :data:`DUPLICATE_RTOL` by default.

    Returns:
        ``keep``, the indices of the rows kept (increasing), and ``inverse``, for each row the
        position in ``keep`` of the row that stands for it.
    """
    r = len(A)
    if r == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    length = np.linalg.norm(A, axis=1)
    length = np.where(length > 0.0, length, 1.0)
    b = np.asarray(offsets, dtype=float).reshape(r, -1)
    key = np.hstack([A / length[:, None], b / (length[:, None] * max(size, 1e-300))])
    # the pairs within rtol in the max-norm, from a k-d tree: comparing every pair of rows cost
    # 4-6 ms for a zonotope's 240 facets against 0.2 ms
    from scipy.spatial import cKDTree

    pairs = cKDTree(key).query_pairs(rtol, p=np.inf, output_type="ndarray")
    leader = np.arange(r)
    for i, j in sorted(map(tuple, pairs.tolist())):  # union by the smaller index: a group's first row leads
        a, c = leader[i], leader[j]
        while leader[a] != a:
            a = leader[a]
        while leader[c] != c:
            c = leader[c]
        leader[max(a, c)] = min(a, c)
    for i in range(r):
        leader[i] = leader[leader[i]]
    keep = np.flatnonzero(leader == np.arange(r))
    position = np.empty(r, dtype=np.intp)
    position[keep] = np.arange(len(keep))
    return keep, position[leader]


def exact_vertices(
    F: np.ndarray, c: np.ndarray, G: np.ndarray, V: np.ndarray, d: np.ndarray, size: float
) -> tuple[np.ndarray, np.ndarray]:
    """Recompute each vertex with its joint values from the zonotope face it lies on.

    A vertex v has F v on the face of Z maximising d = the sum of its facets' zonotope
    normals: y_j = sign(g_j . d) where g_j . d != 0, free otherwise. Solving
    F v - G_free y_free = c + G_fixed y_fixed (square for a vertex in general position; one
    batched solve) gives v and its joint values to round-off; Qhull's vertex, accurate to
    the conditioning of its facets, is kept where this does not confirm it.

    Args:
        F, c, G: the polytope's map (p, m), centre (p,) and generators (p, n).
        V: the vertices as Qhull found them, (v, m).
        d: per vertex, the sum of the zonotope normals of its facets, (v, p).
        size: the set's size (m), the scale of the agreement test.

    Returns:
        The vertices, (v, m), and the box coordinates reaching each, (v, n) (NaN rows where
        they could not be recovered this way).
    """
    (p, m), n = F.shape, G.shape[1]
    proj = d @ G
    fixed = np.abs(proj) > 1e-9 * np.linalg.norm(d, axis=1, keepdims=True) * np.linalg.norm(G, axis=0)
    Y = np.where(fixed, np.sign(proj), 0.0)
    target = c + Y @ G.T
    free_count = n - fixed.sum(axis=1)
    exact, ok = V.copy(), np.zeros(len(V), dtype=bool)
    generic = np.flatnonzero(free_count == p - m)
    if len(generic):
        free = np.argsort(fixed[generic], axis=1, kind="stable")[:, : p - m]  # free columns first
        M = np.concatenate([np.broadcast_to(F, (len(generic), p, m)), -G.T[free].transpose(0, 2, 1)], axis=2)
        with np.errstate(all="ignore"):
            try:
                x = np.linalg.solve(M, target[generic][:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                x = np.full((len(generic), p), np.nan)
        good = np.all(np.isfinite(x), axis=1) & np.all(np.abs(x[:, m:]) <= 1.0 + 1e-9, axis=1)
        good &= np.max(np.abs(x[:, :m] - V[generic]), axis=1) <= 1e-6 * size
        rows = generic[good]
        exact[rows] = x[good, :m]
        Y[rows[:, None], free[good]] = x[good, m:]
        ok[rows] = True
    rest = np.flatnonzero(~ok)  # more free generators than p - m (e.g. parallel generators)
    if len(rest):
        width = int(free_count[rest].max())
        free = np.argsort(fixed[rest], axis=1, kind="stable")[:, :width]
        valid = np.arange(width)[None, :] < free_count[rest][:, None]
        cols = np.where(valid[:, None, :], -G.T[free].transpose(0, 2, 1), 0.0)  # zero padding
        M = np.concatenate([np.broadcast_to(F, (len(rest), p, m)), cols], axis=2)
        M_pinv = np.linalg.pinv(M, rcond=RANK_RTOL)
        x = (M_pinv @ target[rest][:, :, None])[:, :, 0]
        # v is pinned down when no null vector of M moves it: (I - M^+ M) has a zero v-block
        moves = np.eye(M.shape[2])[None, :m] - (M_pinv @ M)[:, :m]
        pinned = np.max(np.abs(moves), axis=(1, 2)) <= 1e-9
        pinned &= np.max(np.abs(x[:, :m] - V[rest]), axis=1) <= 1e-6 * size
        exact[rest[pinned]] = x[pinned, :m]
        inside = pinned & np.all(np.abs(x[:, m:]) <= 1.0 + 1e-9, axis=1)
        for j in np.flatnonzero(inside):
            Y[rest[j], free[j, valid[j]]] = x[j, m:][valid[j]]
        ok[rest[inside]] = True
    return exact, np.where(ok[:, None], np.clip(Y, -1.0, 1.0), np.nan)


def halfspace_vertices(An: np.ndarray, s: np.ndarray, dim: int) -> np.ndarray:
    """The vertices u of {u : An u <= s} (k-dimensional, the origin strictly inside), (v, k).

    Up to 3 dimensions through :func:`mobmanip.sets.hull.enumerate_hull`; above, Qhull's
    halfspace intersection (joggled when nearly degenerate) with coincident vertices merged.

    Raises:
        TaskError: more than :data:`MAX_HIGH_DIM_ROWS` halfspaces above 3 dimensions (``dim``,
            the task dimension, is named in the message).
    """
    from scipy.spatial import HalfspaceIntersection, QhullError

    k = An.shape[1]
    if k <= 3:
        return enumerate_hull(An, s).vertices
    if len(An) > MAX_HIGH_DIM_ROWS:
        raise TaskError(
            f"this {dim}-D polytope has {len(An)} halfspaces: enumerating its vertices (for its "
            "volume or isotropy) is impractical; use support, contains, project or slice"
        )
    halfspaces = np.hstack([An, -s[:, None]])
    try:
        U = HalfspaceIntersection(halfspaces, np.zeros(k)).intersections
    except QhullError:  # nearly degenerate input: Qhull's joggle, accurate to ~1e-10
        U = HalfspaceIntersection(halfspaces, np.zeros(k), qhull_options="QJ").intersections
    return U[_groups(U)[1]]


def volume_from_vertices(V: np.ndarray, triangles: np.ndarray, center: np.ndarray) -> float:
    """The volume enclosed by a polytope's vertices: a segment's length (m = 1), a polygon's area
    (m = 2, vertices in boundary order), or, for m = 3, the sum of the tetrahedra from
    ``center`` to its outward-oriented boundary ``triangles``; above 3, the convex hull's
    (joggled when nearly degenerate)."""
    m = V.shape[1]
    if m == 1:
        return float(abs(V[1, 0] - V[0, 0]))
    if m == 2:
        x, y = V[:, 0], V[:, 1]
        return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if m <= 3:
        T = V[triangles] - center
        return float(abs(np.einsum("ti,ti->t", T[:, 0], np.cross(T[:, 1], T[:, 2])).sum()) / 6.0)
    from scipy.spatial import ConvexHull, QhullError

    try:
        return float(ConvexHull(V).volume)
    except QhullError:  # nearly degenerate vertex set: Qhull's joggle (accurate to ~1e-7)
        return float(ConvexHull(V, qhull_options="QJ").volume)
