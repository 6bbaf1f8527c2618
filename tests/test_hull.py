"""The planar hull routine (no Qhull) against Qhull's halfspace intersection, on awkward inputs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import HalfspaceIntersection

from mobmanip.sets.hull import enumerate_hull


def _qhull_vertices(An, s):
    """Distinct vertices of {u : An u <= s} from scipy's halfspace intersection."""
    points = HalfspaceIntersection(np.hstack([An, -s[:, None]]), np.zeros(2)).intersections
    scale = np.abs(points).max()
    distinct = []
    for p in points:
        if all(np.abs(p - q).max() > 1e-9 * scale for q in distinct):
            distinct.append(p)
    return np.array(distinct)


def _check(An, s):
    hull = enumerate_hull(An, s)
    V = hull.vertices
    reference = _qhull_vertices(An, s)
    scale = np.abs(reference).max()
    assert len(V) == len(reference)
    for p in reference:  # the same vertex set
        assert np.abs(V - p).max(axis=1).min() <= 1e-9 * scale
    assert np.all(An @ V.T <= s[:, None] + 1e-9 * np.abs(s).max())  # every vertex feasible
    angle = np.arctan2(V[:, 1], V[:, 0])
    assert np.all(np.diff(angle) > 0)  # counter-clockwise from the smallest angle
    assert len(hull.facet_rows) == len(V) and len(hull.faces) == len(V)
    for e, (row, (a, b)) in enumerate(zip(hull.facet_rows, hull.faces)):
        assert (a, b) == (e, (e + 1) % len(V))  # boundary order
        for u in (V[a], V[b]):  # both ends lie on the edge's line
            assert abs(An[row] @ u - s[row]) <= 1e-9 * max(abs(s[row]), 1.0)
    assert sorted(map(tuple, hull.pairs.tolist())) == sorted(
        [(e, e) for e in range(len(V))] + [(e, (e + 1) % len(V)) for e in range(len(V))]
    )
    return hull


def test_random_polygons_match_qhull():
    rng = np.random.default_rng(7)
    for _ in range(300):
        rows = int(rng.integers(3, 80))
        An = rng.normal(size=(rows, 2))
        s = rng.uniform(0.2, 3.0, size=rows)
        # make sure the set is bounded: add a triangle around the origin
        An = np.vstack([An, [[1.0, 0.0], [-0.5, 0.9], [-0.5, -0.9]]])
        s = np.r_[s, 5.0, 5.0, 5.0]
        _check(An, s)


def test_duplicate_parallel_and_redundant_rows():
    square = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    # the same halfspaces twice, once scaled, plus parallel looser rows
    An = np.vstack([square, 2.0 * square, square])
    s = np.r_[np.ones(4), 2.0 * np.ones(4), 1.5 * np.ones(4)]
    hull = _check(An, s)
    assert len(hull.vertices) == 4


def test_several_lines_through_one_vertex():
    # five lines through (1, 1), and the two axes' lower bounds
    angles = np.linspace(0.1, np.pi / 2 - 0.1, 5)
    normals = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    An = np.vstack([normals, [[-1.0, 0.0], [0.0, -1.0]]])
    s = np.r_[normals @ np.ones(2), 1.0, 1.0]
    hull = _check(An, s)
    assert np.abs(hull.vertices - [1.0, 1.0]).max(axis=1).min() <= 1e-12


@pytest.mark.parametrize("far_first", [True, False])
def test_rows_on_the_cut_at_pi(far_first):
    # two rows pointing exactly along -x (angle +pi); only the tighter one is a facet
    back = [[-1.0, 0.0], [-2.0, 0.0]] if far_first else [[-2.0, 0.0], [-1.0, 0.0]]
    An = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, -1.0], *back])
    s = np.ones(5) if far_first else np.r_[1.0, 1.0, 1.0, 1.0, 1.0]
    hull = _check(An, s)
    assert len(hull.vertices) == 4


def test_lines_through_one_vertex_up_to_round_off():
    # as the shadows of intersected sets give: several lines through a vertex, each off by ~1e-11
    rng = np.random.default_rng(11)
    angles = np.linspace(0.1, np.pi / 2 - 0.1, 7)
    normals = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    An = np.vstack([normals, -normals])
    s = np.r_[normals @ np.ones(2), normals @ np.ones(2)] + rng.uniform(-1e-11, 1e-11, size=14)
    hull = _check(An, s)
    assert len(hull.vertices) == 4  # a rhombus: the two vertices where the 7 lines meet, two others
    assert np.abs(hull.vertices - [1.0, 1.0]).max(axis=1).min() <= 1e-9
