"""The compiled face enumeration of 2-D and 3-D zonotopes against its NumPy reference and Qhull.

References: :func:`mobmanip.sets.zonotope.low_dim_faces_numpy` (the NumPy construction the kernel
replaces on the hot path), scipy's ``ConvexHull`` of all 2^n corners (independent of both), and
the general route of :class:`Polytope` (facet normals of every generator subset, then Qhull).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from mobmanip.sets import zonotope as zonotope
from mobmanip.sets import zonotope_kernel as zonotope_kernel
from mobmanip.sets.polytope import Polytope

pytest.importorskip("numba")


def _random_generators(rng, trial):
    """Random generators in R^2 or R^3, every fourth case with parallel, coplanar or zero ones."""
    m = 2 + trial % 2
    n = int(rng.integers(m, 9))
    G = rng.normal(size=(m, n))
    kind = (trial // 2) % 4
    if kind == 1:  # parallel copies, same and opposite sense
        G[:, -1] = -2.5 * G[:, 0]
        if n > m + 1:
            G[:, -2] = 0.5 * G[:, 1]
    elif kind == 2 and m == 3:  # three or more coplanar generators (parallel joint axes)
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        q = int(rng.integers(3, n + 1)) if n >= 3 else n
        G[:, :q] -= np.outer(normal, normal @ G[:, :q])
        if n - q >= 3 and trial % 3 == 0:  # a second coplanar family
            other = rng.normal(size=3)
            other /= np.linalg.norm(other)
            G[:, q:] -= np.outer(other, other @ G[:, q:])
    elif kind == 3:
        G[:, 0] = 0.0
    return G, rng.normal(size=m)


def _same_cycle(f, g) -> bool:
    f, g = [int(x) for x in f], [int(x) for x in g]
    if len(f) != len(g) or f[0] not in g:
        return False
    i = g.index(f[0])
    return g[i:] + g[:i] == f


def test_compiled_faces_equal_the_numpy_reference(rng):
    """Same vertices (same order), sign vectors, halfspaces and faces (up to where each face's
    cycle starts) to 1e-9 of the generators' size, on random zonotopes incl. parallel, coplanar
    and zero generators; both decline the same (flat) sets."""
    checked = {2: 0, 3: 0, "coplanar": 0}
    for trial in range(1200):
        G, c = _random_generators(rng, trial)
        fast, ref = zonotope_kernel.faces(c, G), zonotope.low_dim_faces_numpy(c, G)
        assert (fast is None) == (ref is None)
        if ref is None:
            assert np.linalg.matrix_rank(G) < G.shape[0]
            continue
        tol = 1e-9 * np.abs(G).sum()
        for key in ("vertices", "Y", "normals", "offsets", "widths"):
            assert fast[key].shape == ref[key].shape, key
            np.testing.assert_allclose(fast[key], ref[key], rtol=0, atol=tol, err_msg=key)
        assert len(fast["faces"]) == len(ref["faces"])
        assert all(_same_cycle(f, g) for f, g in zip(fast["faces"], ref["faces"]))
        checked[G.shape[0]] += 1
        checked["coplanar"] += any(len(f) > 4 for f in fast["faces"])
    assert checked[2] >= 500 and checked[3] >= 500 and checked["coplanar"] >= 100


def test_compiled_faces_against_the_hull_of_all_corners(rng):
    """Vertices are the convex hull's (Qhull on all 2^n corners) and are reached by their sign
    vectors; every facet's halfspace holds for every corner and is tight on its face's vertices."""
    for trial in range(200):
        G, c = _random_generators(rng, trial)
        if np.linalg.matrix_rank(G) < G.shape[0]:  # flat: polytopes take the general route
            continue
        out = zonotope_kernel.faces(c, G)
        assert out is not None
        n = G.shape[1]
        signs = ((np.arange(2**n)[:, None] >> np.arange(n)) & 1) * 2.0 - 1.0
        corners = c + signs @ G.T
        hull = ConvexHull(corners)
        V, scale = out["vertices"], np.abs(G).sum()
        assert len(V) == len(hull.vertices)
        for v in corners[hull.vertices]:
            assert np.min(np.linalg.norm(V - v, axis=1)) <= 1e-9 * scale
        np.testing.assert_allclose(V, c + out["Y"] @ G.T, rtol=0, atol=1e-12 * scale)
        b = out["offsets"] + out["widths"]
        assert np.all(corners @ out["normals"].T <= b + 1e-9 * scale)
        for face, normal, bound in zip(out["faces"], out["normals"], b):
            np.testing.assert_allclose(V[face] @ normal, bound, rtol=0, atol=1e-9 * scale)


def test_fast_route_equals_the_general_route_of_the_polytope(rng):
    """A zonotope's vertices and halfspaces from the compiled kernel equal those of the general
    route (all generator subsets' normals, then Qhull), which a membership query taken first forces."""
    for trial in range(120):
        G, c = _random_generators(rng, trial)
        if np.linalg.matrix_rank(G) < G.shape[0]:
            continue
        fast = Polytope.zonotope(c, G)
        general = Polytope.zonotope(c, G)
        general.contains(c)  # builds the subset halfspaces: the vertices then come from Qhull
        scale = np.abs(G).sum()
        V, W = fast.vertices, general.vertices
        assert len(V) == len(W)
        assert np.max(np.min(np.linalg.norm(V[:, None] - W[None], axis=2), axis=1)) <= 1e-9 * scale
        (A, b), (A2, b2) = fast.halfspaces, general.halfspaces
        rows, rows2 = np.hstack([A, b[:, None]]), np.hstack([A2, b2[:, None]])
        assert len(rows) == len(rows2)
        assert np.max(np.min(np.abs(rows[:, None] - rows2[None]).max(axis=2), axis=1)) <= 1e-9 * max(scale, 1.0)
