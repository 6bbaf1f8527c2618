"""Vertices and faces of a bounded polytope {u in R^k : An u <= s}, k <= 3, around an interior point.

The origin must lie strictly inside (every slack s_i > 0). The polar set around it is the convex
hull of the points w_i = An_i / s_i: its facets are the polytope's vertices (a facet
{w : nu . w = -o} gives the vertex u = nu / -o) and its vertices are the polytope's facets. One
Qhull call (``scipy.spatial.ConvexHull``) therefore gives vertices, facets and their incidence.
Qhull triangulates its output, so a vertex where more than k facets meet comes out once per
triangle of its polar facet; those copies (equal to round-off) are merged.

In the plane (k = 2) the polar hull is found without Qhull, by a few array passes over the polar
points in angular order (see :func:`_polygon`): for the few dozen rows of a capacity polygon
that costs less than a Qhull call with its set-up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Copies of one vertex agree to round-off; distinct vertices are farther apart than this
#: fraction of the set's size.
MERGE_RTOL = 1e-9


@dataclass(frozen=True)
class Hull:
    """Vertices and faces of a polytope in its own coordinates u (k = 1..3).

    Attributes:
        vertices: (v, k); counter-clockwise when k = 2.
        facet_rows: the rows that are facets (irredundant), (f,).
        faces: per facet, its vertices (k = 3: counter-clockwise seen from outside; k = 2: the
            edge's two ends, in boundary order; k = 1: the end point).
        pairs: incidences (facet index, vertex index), (i, 2), sorted by facet.
    """

    vertices: np.ndarray
    facet_rows: np.ndarray
    faces: list[np.ndarray]
    pairs: np.ndarray

    def normal_sums(self, rows: np.ndarray) -> np.ndarray:
        """Per vertex, the sum of ``rows[facet]`` over the facets that meet there, (v, cols)."""
        out = np.zeros((len(self.vertices), rows.shape[1]))
        np.add.at(out, self.pairs[:, 1], rows[self.pairs[:, 0]])
        return out


def enumerate_hull(An: np.ndarray, s: np.ndarray) -> Hull:
    """Vertices and faces of {u in R^k : An u <= s} with s > 0 (the origin strictly inside).

    Args:
        An: rows, (rows, k), k in 1..3; rows that vanish (parallel to the whole set) are ignored.
        s: slacks at the interior point, all positive, (rows,).
    """
    k = An.shape[1]
    length = np.linalg.norm(An, axis=1)
    use = np.flatnonzero(length > 1e-12 * max(float(length.max(initial=0.0)), 1e-300))
    W = An[use] / s[use, None]  # polar points
    if k == 1:
        w = W[:, 0]
        lo, hi = int(np.argmin(w)), int(np.argmax(w))  # w[lo] < 0 < w[hi]
        ends = np.array([[1.0 / w[lo]], [1.0 / w[hi]]])
        return Hull(ends, use[[lo, hi]], [np.array([0]), np.array([1])], np.array([[0, 0], [1, 1]]))
    if k == 2:
        return _polygon(W, use)
    from scipy.spatial import ConvexHull  # loaded at the first hull (about 0.08 s)

    hull = ConvexHull(W)
    eq = hull.equations
    U = eq[:, :k] / -eq[:, k:]
    group, first = _groups(U)
    U = U[first]
    # Incidence polar vertex (our facet) x polar facet (our vertex), from the triangulation.
    key = np.unique(hull.simplices.ravel().astype(np.int64) * len(U) + np.repeat(group, k))
    row, vertex = key // len(U), key % len(U)
    # A row that touches the set in fewer than k distinct vertices (its polar point lies on the
    # hull but its candidate vertices merged into one) is no facet: a zero-size face.
    rows, count = np.unique(row, return_counts=True)
    keep = np.isin(row, rows[count >= k])
    row, vertex = row[keep], vertex[keep]
    facets, facet = np.unique(row, return_inverse=True)
    counts = np.bincount(facet)
    if k == 2:
        order = np.argsort(np.arctan2(U[:, 1], U[:, 0]))
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        ends = np.sort(rank[vertex].reshape(-1, 2), axis=1)  # every polygon edge has two ends
        wrap = (ends[:, 0] == 0) & (ends[:, 1] == len(U) - 1)
        ends[wrap] = ends[wrap][:, ::-1]
        edge_order = np.argsort(ends[:, 0])
        position = np.empty_like(edge_order)
        position[edge_order] = np.arange(len(edge_order))
        pairs = np.stack([position[facet], rank[vertex]], axis=1)
        pairs = pairs[np.argsort(pairs[:, 0], kind="stable")]
        return Hull(U[order], use[facets][edge_order], list(ends[edge_order]), pairs)
    # k = 3: order each facet's vertices by angle around its centroid, in the facet's plane.
    normal = W[facets] / np.linalg.norm(W[facets], axis=1, keepdims=True)
    helper = np.where(np.abs(normal[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(normal, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(normal, e1)
    centroid = np.stack([np.bincount(facet, U[vertex, i]) for i in range(3)], axis=1) / counts[:, None]
    rel = U[vertex] - centroid[facet]
    angle = np.arctan2(np.einsum("ij,ij->i", rel, e2[facet]), np.einsum("ij,ij->i", rel, e1[facet]))
    ordered = vertex[np.lexsort((angle, facet))]
    faces = np.split(ordered, np.cumsum(counts)[:-1])
    return Hull(U, use[facets], faces, np.stack([facet, vertex], axis=1))


def _polygon(W: np.ndarray, use: np.ndarray) -> Hull:
    """The polygon whose polar points (rows ``use`` of the caller) are W, (r, 2)."""
    radius = np.hypot(W[:, 0], W[:, 1])
    angle = np.arctan2(W[:, 1], W[:, 0])
    order = np.argsort(angle)
    ray = np.cumsum(np.diff(angle[order], prepend=-np.inf) > 1e-12) - 1  # one number per ray
    if angle[order[0]] + 2.0 * np.pi - angle[order[-1]] <= 1e-12:  # a ray along the cut at +-pi
        ray[ray == ray[-1]] = 0
    if ray[-1] < len(ray) - 1:  # of points on one ray only the farthest can be on the hull
        by_ray = np.lexsort((-radius[order], ray))
        order, ray = order[by_ray], ray[by_ray]
        order = order[np.diff(ray, prepend=-1) > 0]
    keep = order
    # Around the origin (inside the hull) the points in angular order form a star-shaped
    # polygon; a hull vertex always turns left in it, so removing every point that does not,
    # pass after pass, leaves the hull.
    # A turn counts as left beyond round-off and a 1e-12 relative collinearity (a point that close
    # to the segment of its neighbours moves no vertex by more than that).
    x, y = W[keep, 0], W[keep, 1]
    scale = float(radius.max())
    while len(x) > 3:
        before, after = np.arange(-1, len(x) - 1), np.arange(1, len(x) + 1)
        after[-1] = 0
        ax, ay, bx, by = x - x[before], y - y[before], x[after] - x, y[after] - y
        la, lb = np.hypot(ax, ay), np.hypot(bx, by)
        left = ax * by - ay * bx > 1e-12 * la * lb + 1e-14 * scale * (la + lb)
        if left.all():
            break
        keep, x, y = keep[left], x[left], y[left]
    if len(x) < 3:
        # Near-duplicate rays across the +-pi cut (a heavy object's box-like polytope: polar points
        # 5e-12 rad apart) can leave too few points to bound the polygon: Qhull decides instead.
        from scipy.spatial import ConvexHull

        keep = ConvexHull(W).vertices  # counter-clockwise in 2-D
        x, y = W[keep, 0], W[keep, 1]
    # Facet i (polar point w_i) and facet i + 1 meet at the vertex u with w_i . u = w_(i+1) . u = 1.
    # A facet whose two vertices coincide to round-off (a third line through a vertex, nearly but
    # not exactly collinear in the polar picture) is no facet: dropped, as Qhull's copies merge.
    while True:
        n = len(keep)
        after = np.arange(1, n + 1)
        after[-1] = 0
        xa, ya = x[after], y[after]
        det = x * ya - y * xa
        U = np.empty((n, 2))
        U[:, 0], U[:, 1] = (ya - y) / det, (x - xa) / det
        edge = np.abs(U[after] - U).max(axis=1)  # the length of facet i + 1's edge
        short = edge <= MERGE_RTOL * np.abs(U).max()
        if not short.any() or n <= 3:
            break
        drop = np.zeros(n, dtype=bool)
        drop[after[np.flatnonzero(short)[:1]]] = True  # one at a time: its neighbours' vertex stays
        keep, x, y = keep[~drop], x[~drop], y[~drop]
    # Vertex j lies between facets j and j + 1: edge e runs from vertex e to e + 1 (cyclically)
    # along facet e + 1; vertices are numbered from the smallest angle, counter-clockwise.
    start = int(np.argmin(np.arctan2(U[:, 1], U[:, 0])))
    U = np.roll(U, -start, axis=0)
    facets = np.roll(keep, -start - 1)
    ends = np.empty((n, 2), dtype=np.intp)
    ends[:, 0], ends[:, 1] = np.arange(n), np.roll(np.arange(n), -1)
    pairs = np.empty((2 * n, 2), dtype=np.intp)
    pairs[:, 0], pairs[:, 1] = np.repeat(np.arange(n), 2), ends.ravel()
    return Hull(U, use[facets], list(ends), pairs)


def _groups(U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Group index of each candidate vertex (copies of one vertex share it) and the first
    candidate of each group, in order of first appearance."""
    n = len(U)
    scale = max(float(np.abs(U).max(initial=0.0)), 1e-300)
    if n <= 128:
        close = np.max(np.abs(U[:, None, :] - U[None, :, :]), axis=2) <= MERGE_RTOL * scale
        leader = np.argmax(close, axis=1)  # the first candidate close to each one
    else:
        from scipy.spatial import cKDTree

        pairs = cKDTree(U).query_pairs(MERGE_RTOL * scale, output_type="ndarray")
        leader = np.arange(n)
        if len(pairs):
            np.minimum.at(leader, pairs[:, 1], pairs[:, 0])
            np.minimum.at(leader, pairs[:, 0], pairs[:, 1])
    leader = leader[leader]  # chains of copies within the tolerance end at their first member
    first, group = np.unique(leader, return_inverse=True)
    return group, first
