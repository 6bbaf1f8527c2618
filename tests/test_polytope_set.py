"""The Polytope set itself, on synthetic zonotopes and zonotope sections.

References: scipy's ``linprog`` written from the definition {a : F a = c + G y, |y| <= 1},
scipy's ``ConvexHull`` volumes, and sets whose numbers are known by hand (a square, a segment,
two boxes that do not meet).
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

import mobmanip
from mobmanip.errors import LimitError, MobmanipError, ModelError, TaskError
from mobmanip.sets import zonotope as zonotope
from mobmanip.sets.capacity import dynamic_polytope, kinematic_polytope, polytope_indices
from mobmanip.sets.polytope import Polytope


def _unit(rng, count, dim):
    d = rng.normal(size=(count, dim))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _lp_support(F, c, G, d, fixed=None):
    """max d . a_D over {a : F a = c + G y, |y| <= 1}; ``fixed`` = {coordinate: value}; d over all
    coordinates (zeros where fixed)."""
    m, n = F.shape[1], G.shape[1]
    bounds = [(None, None)] * m + [(-1, 1)] * n
    for k, v in (fixed or {}).items():
        bounds[k] = (v, v)
    res = linprog(np.r_[-d, np.zeros(n)], A_eq=np.hstack([F, -G]), b_eq=c, bounds=bounds, method="highs")
    assert res.status == 0
    return -res.fun


def _section(rng, m, p, n, symmetric=True):
    F = rng.normal(size=(p, m))
    G = rng.normal(size=(p, n))
    c = F @ rng.normal(size=m) if symmetric else 0.3 * rng.normal(size=p)
    return F, c, G


@pytest.mark.parametrize("m, p, n", [(2, 2, 7), (2, 4, 8), (3, 3, 9), (3, 6, 12)])
def test_vertices_and_halfspaces_against_linear_programs(rng, m, p, n):
    for symmetric in (True, False):
        F, c, G = _section(rng, m, p, n, symmetric)
        poly = Polytope(F, c, G)
        if poly.empty:
            continue
        d = _unit(rng, 40, m)
        ref = np.array([_lp_support(F, c, G, x) for x in d])
        np.testing.assert_allclose(poly.supports(d), ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())
        A, b = poly.halfspaces
        V = poly.vertices
        slack = b[:, None] - A @ V.T
        assert slack.min() >= -1e-9 * np.abs(b).max()
        tight = slack <= 1e-9 * np.abs(b).max()
        assert np.all(tight.sum(axis=1) >= m)  # every row is a facet: m vertices on it
        assert np.all(tight.sum(axis=0) >= m)  # every vertex meets m facets
        assert poly.contains(V).all()


def test_box_scaled_past_its_limits_leaves_the_set(rng):
    F, c, G = _section(rng, 3, 6, 10)
    poly = Polytope(F, c, G)
    outward = poly.center + 1.001 * (poly.vertices - poly.center)  # needs 1.001 of some limit
    inward = poly.center + 0.999 * (poly.vertices - poly.center)
    assert not poly.contains(outward, tol=1e-9).any()
    assert poly.contains(outward, tol=2e-3).all()
    assert poly.contains(inward, tol=0.0).all()


def test_square_has_the_numbers_known_by_hand():
    square = Polytope.zonotope([1.0, 2.0], np.eye(2))  # [0, 2] x [1, 3]
    assert square.volume == pytest.approx(4.0, rel=1e-14)
    assert square.inradius == pytest.approx(1.0, rel=1e-14)
    assert square.circumradius == pytest.approx(math.sqrt(2.0), rel=1e-14)
    assert square.isotropy == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-14)
    assert square.support([1.0, 1.0]) == pytest.approx(2.0 + 3.0)
    assert square.radius_along([0.0, 5.0]) == pytest.approx(1.0)
    assert square.radius_along([1.0, 1.0]) == pytest.approx(math.sqrt(2.0))  # the corner's extent
    np.testing.assert_allclose(np.sort(square.vertices, axis=0), [[0, 1], [0, 1], [2, 3], [2, 3]], atol=1e-15)
    np.testing.assert_allclose(square.chebyshev_center, [1.0, 2.0])


def test_zonotope_volume_closed_form_equals_hull_volume(rng):
    for m, n in ((2, 6), (3, 8), (3, 16)):
        poly = Polytope.zonotope(rng.normal(size=m), rng.normal(size=(m, n)))
        assert poly.volume == pytest.approx(ConvexHull(poly.vertices).volume, rel=1e-10)
        # the closed form counts every vertex too: 2 sum_{k<m} C(n-1, k)
        assert len(poly.vertices) == 2 * sum(math.comb(n - 1, k) for k in range(m))


def test_section_volume_from_faces_equals_hull_volume(rng):
    F, c, G = _section(rng, 3, 6, 12, symmetric=False)
    poly = Polytope(F, c, G)
    assert not poly.empty
    assert poly.volume == pytest.approx(ConvexHull(poly.vertices).volume, rel=1e-10)


def test_faces_are_outward_polygons_on_their_facets(rng):
    F, c, G = _section(rng, 3, 6, 12)
    poly = Polytope(F, c, G)
    A, b = poly.halfspaces
    V = poly.vertices
    assert len(poly.faces) == len(A)
    for row, face in enumerate(poly.faces):
        np.testing.assert_allclose(V[face] @ A[row], b[row], atol=1e-9 * np.abs(b).max())
    T = V[poly.triangles]
    normals = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    assert np.all(np.einsum("ij,ij->i", normals, T[:, 0] - poly.center) > 0)  # outward
    area = 0.5 * np.linalg.norm(normals, axis=1).sum()
    assert area == pytest.approx(ConvexHull(V).area, rel=1e-10)
    poly2 = Polytope(*_section(rng, 2, 4, 8))
    P = poly2.vertices - poly2.center
    assert np.all(P[:, 0] * np.roll(P[:, 1], -1) - P[:, 1] * np.roll(P[:, 0], -1) > 0)  # counter-clockwise


def test_projection_and_slice_of_a_six_dimensional_section(rng):
    F, c, G = _section(rng, 6, 12, 16, symmetric=False)
    poly = Polytope(F, c, G)
    assert not poly.empty
    dims = [0, 2, 4]
    shadow = poly.project(dims)
    cut = poly.slice(dims)
    rest = [1, 3, 5]
    for d in _unit(rng, 20, 3):
        full = np.zeros(6)
        full[dims] = d
        assert shadow.support(d) == pytest.approx(_lp_support(F, c, G, full), rel=1e-9, abs=1e-9)
        fixed = {k: poly.center[k] for k in rest}
        assert cut.support(d) == pytest.approx(_lp_support(F, c, G, full, fixed), rel=1e-9, abs=1e-9)
        assert poly.support(full) == pytest.approx(_lp_support(F, c, G, full), rel=1e-9, abs=1e-9)
    assert shadow.contains(cut.vertices).all()  # a cut lies inside the shadow


def test_least_effort_center_and_chebyshev_ball(rng):
    F, c, G = _section(rng, 3, 8, 8, symmetric=False)
    poly = Polytope(F, c, G)
    (p, m), n = F.shape, G.shape[1]
    # min t subject to F a - G y = c, -t <= y <= t, written independently
    A_ub = np.vstack([np.hstack([np.zeros((n, m)), np.eye(n), -np.ones((n, 1))])] * 2)
    A_ub[n:, m : m + n] *= -1
    res = linprog(
        np.r_[np.zeros(m + n), 1.0],
        A_ub=A_ub,
        b_ub=np.zeros(2 * n),
        A_eq=np.hstack([F, -G, np.zeros((p, 1))]),
        b_eq=c,
        bounds=[(None, None)] * (m + n) + [(0, None)],
        method="highs",
    )
    assert poly.least_effort == pytest.approx(res.fun, rel=1e-9)
    A, b = poly.halfspaces
    r, x = poly.chebyshev_radius, poly.chebyshev_center
    assert np.all(A @ x + r <= b + 1e-9)
    res = linprog(np.r_[np.zeros(m), -1.0], A_ub=np.hstack([A, np.ones((len(A), 1))]), b_ub=b, method="highs")
    assert r == pytest.approx(-res.fun, rel=1e-8)


def test_two_boxes_that_do_not_meet_are_empty_and_touching_ones_are_a_point():
    apart = Polytope([[1.0], [1.0]], [0.0, 3.0], np.eye(2))  # a in [-1, 1] and a in [2, 4]
    assert apart.empty and apart.degenerate and apart.least_effort == pytest.approx(1.5)
    assert apart.volume == 0 and apart.support([1.0]) == 0 and not apart.contains([[0.0]]).any()
    touching = Polytope([[1.0], [1.0]], [0.0, 2.0], np.eye(2))  # only a = 1
    assert not touching.empty and touching.degenerate
    np.testing.assert_allclose(touching.vertices, [[1.0]], atol=1e-9)


def test_flat_sets_are_degenerate_with_equalities(rng):
    plane = rng.normal(size=(3, 2))
    flat = Polytope.zonotope(np.zeros(3), plane @ rng.normal(size=(2, 6)))  # generators in a plane
    normal = np.cross(plane[:, 0], plane[:, 1])
    assert flat.degenerate and not flat.empty and flat.volume == 0.0 and flat.isotropy == 0.0
    assert np.abs(flat.vertices @ normal).max() <= 1e-9
    assert len(flat.faces) == len(flat.vertices) >= 4 and len(flat.triangles) == len(flat.vertices) - 2
    A, b = flat.halfspaces
    assert flat.contains(flat.vertices).all() and flat.contains(0.01 * normal) is False
    assert np.all(A @ (0.5 * flat.vertices[0]) <= b + 1e-12)
    segment = Polytope.zonotope([1.0, 1.0], [[1.0, 2.0], [1.0, 2.0]])
    np.testing.assert_allclose(np.sort(segment.vertices[:, 0]), [-2.0, 4.0], atol=1e-12)
    point = Polytope.zonotope([1.0, 2.0, 3.0], np.zeros((3, 4)))
    np.testing.assert_allclose(point.vertices, [[1.0, 2.0, 3.0]])
    assert point.degenerate and point.volume == 0.0


def test_inputs_reach_points_within_their_limits(rng):
    F, c, G = _section(rng, 3, 6, 10, symmetric=False)
    limits = rng.uniform(0.5, 3.0, size=10)
    poly = Polytope(F, c, G * limits, limits)
    w = rng.dirichlet(np.ones(len(poly.vertices)), size=5)
    points = w @ poly.vertices
    for p, x in zip(points, poly.inputs(points)):
        assert np.all(np.abs(x) <= limits * (1 + 1e-9))
        np.testing.assert_allclose(F @ p, c + G @ x, atol=1e-9)
    X = poly.vertex_inputs
    assert np.all(np.abs(X) <= limits * (1 + 1e-12))
    np.testing.assert_allclose(poly.vertices @ F.T, c + X @ G.T, atol=1e-10)
    with pytest.raises(TaskError, match="outside the polytope"):
        poly.inputs(poly.center + 1.01 * (poly.vertices[0] - poly.center))


def test_too_many_candidate_facets_fall_back_to_linear_programs(rng):
    F = np.vstack([np.eye(6), np.eye(6)])
    G = rng.normal(size=(12, 40))  # C(40, 11) candidate facets
    poly = Polytope(F, np.zeros(12), G)
    assert zonotope.subset_count(40, 11) > zonotope.MAX_SUBSETS
    assert poly.contains(np.zeros(6)) is True
    d = _unit(rng, 3, 6)
    np.testing.assert_allclose(poly.supports(d), [_lp_support(F, np.zeros(12), G, x) for x in d], rtol=1e-9)
    far = 1.001 * poly.support(d[0]) * d[0] / (d[0] @ d[0])
    assert poly.contains(far) is False
    with pytest.raises(TaskError, match="candidate facets"):
        poly.halfspaces  # noqa: B018
    assert poly.to_dict()["halfspaces"] is None


def test_pickled_polytope_answers_the_same(rng):
    poly = Polytope(*_section(rng, 6, 12, 14))
    d = _unit(rng, 4, 6)
    before = poly.supports(d)  # builds the warm linear program
    again = pickle.loads(pickle.dumps(poly))
    np.testing.assert_array_equal(again.supports(d), before)


def test_bad_input_names_what_is_wrong(rng):
    with pytest.raises(TaskError, match="shape"):
        Polytope(np.eye(2), np.zeros(3), np.eye(2))
    with pytest.raises(TaskError, match="not injective"):
        Polytope([[1.0, 1.0], [2.0, 2.0]], np.zeros(2), np.eye(2))
    with pytest.raises(TaskError, match="non-finite"):
        Polytope.zonotope([0.0, np.nan], np.eye(2))
    poly = Polytope.zonotope(np.zeros(6), rng.normal(size=(6, 8)))
    with pytest.raises(TaskError, match="up to 3"):
        poly.vertices  # noqa: B018
    with pytest.raises(TaskError, match="dims"):
        poly.project((0, 0))
    with pytest.raises(TaskError, match="non-zero"):
        poly.radius_along(np.zeros(6))
    J, W = rng.normal(size=(4, 6)), np.hstack([np.eye(2), np.eye(2)])
    with pytest.raises(LimitError, match="velocity limit"):
        kinematic_polytope(J, W, -np.ones(6))
    with pytest.raises(TaskError, match="full row rank"):
        kinematic_polytope(J, np.zeros((2, 4)), np.ones(6))
    with pytest.raises(ModelError, match="without mass"):
        dynamic_polytope(J, W, np.zeros((6, 6)), np.eye(6), np.zeros(6), np.zeros((2, 2)), np.zeros(2), np.ones(6))
    assert issubclass(TaskError, MobmanipError) and issubclass(ModelError, MobmanipError)


def test_batch_indices_are_those_of_each_configuration(robot, rng):
    from conftest import random_configurations

    qs = random_configurations(robot, rng, 4)
    analyses = [mobmanip.analyze(robot, q, "planar", method="exact") for q in qs]
    J = np.array([a.unified_jacobian for a in analyses])
    W = np.array([a.grasp_matrix for a in analyses])
    d = _unit(rng, 3, 2)
    batch = polytope_indices("kinematic", directions=d, J_u=J, W=W, velocity_limits=robot.velocity_limits)
    for i, a in enumerate(analyses):
        single = kinematic_polytope(a.unified_jacobian, a.grasp_matrix, robot.velocity_limits)
        assert batch.volume[i] == pytest.approx(single.volume, rel=1e-12)
        assert batch.isotropy[i] == pytest.approx(single.isotropy, rel=1e-12)
        np.testing.assert_allclose(batch.support[i], single.supports(d), rtol=1e-12)
        np.testing.assert_allclose(batch.radius_along[i], [single.radius_along(x) for x in d], rtol=1e-12)
    with pytest.raises(TaskError, match="unknown polytope kind"):
        polytope_indices("nope", J_u=J, W=W)


def test_six_dimensional_volumes_against_brute_force(rng):
    G = rng.normal(size=(6, 8))
    zono = Polytope.zonotope(np.zeros(6), G)
    signs = ((np.arange(2**8)[:, None] >> np.arange(8)) & 1) * 2.0 - 1.0
    corners = signs @ G.T
    assert zono.volume == pytest.approx(ConvexHull(corners).volume, rel=1e-9)
    assert zono.circumradius == pytest.approx(np.linalg.norm(corners, axis=1).max(), rel=1e-12)
    # a box section with few halfspaces: every vertex solves 6 of them, found by brute force
    F, c = rng.normal(size=(9, 6)), 0.2 * rng.normal(size=9)
    poly = Polytope(F, c, np.eye(9))
    A, b = np.vstack([F, -F]), np.concatenate([1.0 + c, 1.0 - c])
    subsets = zonotope.combinations(18, 6)
    subsets = subsets[np.all(np.sort(subsets % 9, axis=1)[:, 1:] != np.sort(subsets % 9, axis=1)[:, :-1], axis=1)]
    M = A[subsets]
    good = np.abs(np.linalg.det(M)) > 1e-9
    X = np.linalg.solve(M[good], b[subsets[good]][:, :, None])[:, :, 0]
    X = X[np.all(X @ A.T <= b + 1e-9, axis=1)]
    assert poly.volume == pytest.approx(ConvexHull(X).volume, rel=1e-7)
    assert poly.circumradius == pytest.approx(np.linalg.norm(X - poly.center, axis=1).max(), rel=1e-9)


def test_3d_zonotopes_with_coplanar_generators_against_the_hull_of_all_corners(rng):
    """Arms with parallel joint axes give coplanar velocity generators: the facets are then
    polygons, built combinatorially. Vertices equal the convex hull of all 2^n corners (Qhull),
    reached by their sign vectors; faces are outward and counter-clockwise; the volume is the
    hull's."""
    checked = 0
    for trial in range(60):
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        plane = rng.normal(size=(3, int(rng.integers(3, 6))))
        plane -= np.outer(normal, normal @ plane)
        G = np.hstack([plane, rng.normal(size=(3, int(rng.integers(0, 4))))])
        if trial % 3 == 0:  # a second family of coplanar generators
            other = rng.normal(size=3)
            other /= np.linalg.norm(other)
            extra = rng.normal(size=(3, 3))
            G = np.hstack([G, extra - np.outer(other, other @ extra)])
        if np.linalg.matrix_rank(G) < 3:  # all in one plane: a flat zonotope (the general route)
            continue
        c = rng.normal(size=3)
        out = zonotope.low_dim_faces(c, G)
        assert out is not None
        signs = ((np.arange(2 ** G.shape[1])[:, None] >> np.arange(G.shape[1])) & 1) * 2.0 - 1.0
        corners = c + signs @ G.T
        hull = ConvexHull(corners)
        V = out["vertices"]
        assert len(V) == len(hull.vertices)
        for v in corners[hull.vertices]:
            assert np.min(np.linalg.norm(V - v, axis=1)) <= 1e-9 * np.abs(G).sum()
        np.testing.assert_allclose(V, c + out["Y"] @ G.T, rtol=0, atol=1e-12 * np.abs(G).sum())
        for face, normal_out in zip(out["faces"], out["normals"]):
            w = V[face]
            turns = np.cross(np.roll(w, -1, axis=0) - w, np.roll(w, -2, axis=0) - np.roll(w, -1, axis=0))
            assert np.all(turns @ normal_out > 0.0)  # convex, counter-clockwise seen from outside
        zono = Polytope.zonotope(c, G)
        assert zono.volume == pytest.approx(hull.volume, rel=1e-9)
        T = zono.vertices[zono.triangles] - c
        assert abs(np.einsum("ti,ti->t", T[:, 0], np.cross(T[:, 1], T[:, 2])).sum()) / 6.0 == pytest.approx(
            hull.volume, rel=1e-9
        )
        checked += 1
    assert checked >= 40
