"""The compiled batch of planar capacity polytopes (the sweeps' path): the same indices as one
:class:`~mobmanip.sets.polytope.Polytope` per configuration, and each index equal to an
independent computation (support programs over the joint box, polygons enumerated from the
defining equations and measured by Qhull)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import mobmanip
from conftest import configuration_within_limits, random_configurations
from mobmanip.errors import ModelError
from mobmanip.sets.capacity import polytope_batch, stacked_terms
from mobmanip.sets.capacity_batch import CompiledPolytopeBatch
from mobmanip.terms.builder import terms_at
from polytope_util import dynamic_lp, kinematic_lp, min_norm_lp, policy_map

KINEMATIC = ("J_u", "W", "velocity_limits")
DYNAMIC = ("J_u", "W", "P", "Q", "xi", "M_o", "g_o", "effort_limits")


def _stacked_terms(robot, qs, decoupled=False) -> dict:
    """The terms of every configuration, stacked (J_u, P, xi per row; the rest shared)."""
    return stacked_terms([terms_at(robot, q, "planar", object_mass=2.0, decoupled=decoupled) for q in qs])


@pytest.fixture(scope="module")
def paper_configurations(robot):
    """300 configurations of the paper robot: 150 random (any joint angles), 150 holding the
    object at random directions in the case study's posture, with random arm perturbations."""
    from mobmanip.casestudy import configuration_at, optimal_posture

    rng = np.random.default_rng(7)
    qs = random_configurations(robot, rng, 150)
    posture = optimal_posture(robot)
    model = robot.model
    arms = [
        model.joints[model.getJointId(f"arm_{side}_{i}_joint")].idx_q for side in ("right", "left") for i in (1, 2, 3)
    ]
    for alpha in rng.uniform(0.0, 360.0, 150):
        q = configuration_at(robot, posture, float(alpha))
        q[arms] += rng.normal(0.0, 0.2, 6)
        qs.append(q)
    return np.array(qs)


@pytest.fixture(scope="module")
def paper_terms(robot, paper_configurations):
    return _stacked_terms(robot, paper_configurations)


@pytest.fixture(scope="module")
def paper_terms_decoupled(robot, paper_configurations):
    """The same with the paper's decoupled inertia (platform-arm blocks of P zero)."""
    return _stacked_terms(robot, paper_configurations, decoupled=True)


def _pick(terms: dict, names) -> dict:
    return {k: terms[k] for k in names}


def _rel(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


@pytest.mark.parametrize("kind, names", [("kinematic", KINEMATIC), ("dynamic", DYNAMIC), ("dynamic_min_norm", DYNAMIC)])
@pytest.mark.parametrize("decoupled", [False, True])
def test_compiled_batch_equals_one_polytope_per_configuration(
    paper_terms, paper_terms_decoupled, kind, names, decoupled
):
    terms = _pick(paper_terms_decoupled if decoupled else paper_terms, names)
    fast = polytope_batch(kind, **terms)
    ref = polytope_batch(kind, compiled=False, **terms)
    assert isinstance(fast, CompiledPolytopeBatch) and fast.computed.all()  # every row compiled
    n = len(ref)
    rng = np.random.default_rng(3)
    d = rng.normal(size=(n, 2))
    assert not fast.empty.any() and not fast.degenerate.any()
    np.testing.assert_array_equal(fast.empty, ref.empty)
    np.testing.assert_array_equal(fast.degenerate, ref.degenerate)
    assert _rel(fast.volume, ref.volume) <= 1e-12
    assert _rel(fast.isotropy, ref.isotropy) <= 1e-12
    for direction in (d, d[0], np.array([1.0, 0.0]), np.array([0.0, -2.0])):
        assert _rel(fast.support(direction), ref.support(direction)) <= 1e-12
        assert _rel(fast.radius_along(direction), ref.radius_along(direction)) <= 1e-12
    assert _rel(fast.widths, ref.widths) <= 1e-12
    # row n is the reference polytope itself
    for i in (0, n // 2, n - 1):
        np.testing.assert_array_equal(fast[i].vertices, ref[i].vertices)


def _kinematic_polygon(J, W, vlim) -> np.ndarray:
    """Vertices (with repeats and interior points) of {v : J x = W^T v, |x| <= vlim}, by brute force.

    Columns (x, v): a vertex of the lifted polytope has n - (mk - m) joint rates at their
    limits; for each choice and sign pattern the rest (the free rates and v) solve J x = W^T v.
    """
    mk, n = J.shape
    m = W.shape[0]
    bound = n - (mk - m)
    points = []
    for at in itertools.combinations(range(n), bound):
        free = [j for j in range(n) if j not in at]
        M = np.hstack([J[:, free], -W.T])  # unknowns: free rates, v
        if abs(np.linalg.det(M)) < 1e-12 * np.abs(M).max() ** M.shape[0]:
            continue
        for signs in itertools.product((-1.0, 1.0), repeat=bound):
            x_at = np.array(signs) * vlim[list(at)]
            z = np.linalg.solve(M, -J[:, list(at)] @ x_at)
            if np.all(np.abs(z[: len(free)]) <= vlim[free] * (1.0 + 1e-12)):
                points.append(z[len(free) :])
    return np.array(points)


def _dynamic_point(J, W, P, Q, xi, M_o, g_o, tau) -> np.ndarray:
    """The object's acceleration at torque tau from the three defining equations solved densely:
    P qdd - Q tau + J^T h = xi, J qdd = W^T a, W h = M_o a + g_o (unknowns qdd, h, a)."""
    mk, n = J.shape
    m = W.shape[0]
    A = np.zeros((n + mk + m, n + mk + m))
    A[:n, :n], A[:n, n : n + mk] = P, J.T
    A[n : n + mk, :n], A[n : n + mk, n + mk :] = J, -W.T
    A[n + mk :, n : n + mk], A[n + mk :, n + mk :] = W, -M_o
    return np.linalg.solve(A, np.r_[xi + Q @ tau, np.zeros(mk), g_o])[n + mk :]


def _dynamic_polygon(J, W, P, Q, xi, M_o, g_o, tau_max) -> tuple[np.ndarray, np.ndarray]:
    """The object accelerations at every torque corner (their hull is the exact dynamic set) and
    at zero torque (its centre), each by :func:`_dynamic_point`."""
    n = J.shape[1]
    corners = [
        _dynamic_point(J, W, P, Q, xi, M_o, g_o, np.array(s) * tau_max)
        for s in itertools.product((-1.0, 1.0), repeat=n)
    ]
    return np.array(corners), _dynamic_point(J, W, P, Q, xi, M_o, g_o, np.zeros(n))


def _assert_volume_and_isotropy(batch, r, hull: ConvexHull, centre: np.ndarray) -> None:
    """Row r's volume (an area in 2-D) and isotropy -- the distance from ``centre`` to the nearest
    facet over that to the farthest vertex -- are the reference hull's (to 1e-12)."""
    corners = hull.points[hull.vertices]
    assert batch.volume[r] == pytest.approx(hull.volume, rel=1e-12)
    inradius = np.min(-(hull.equations[:, :-1] @ centre + hull.equations[:, -1]))
    circumradius = np.max(np.linalg.norm(corners - centre, axis=1))
    assert batch.isotropy[r] == pytest.approx(inradius / circumradius, rel=1e-12)


def _reach(hull: ConvexHull, u: np.ndarray) -> float:
    """The largest s with s u in the hull (the origin inside): the nearest facet along u."""
    normal, offset = hull.equations[:, :2], hull.equations[:, 2]
    along = normal @ u
    return float(np.min(-offset[along > 0] / along[along > 0]))


def _min_norm_polygon(J, W, P, Q, xi, M_o, g_o, tau_max) -> np.ndarray:
    """Vertices (with repeats) of {a : |Lambda_o a + mu_o| <= tau_max}: every pair of the 2 n
    boundary lines intersected, kept where every torque is within its limit (numpy's pinv)."""
    Lam, mu = policy_map(J, W, P, Q, xi, M_o, g_o)
    lines = [(Lam[i], side * tau_max[i] - mu[i]) for i in range(len(mu)) for side in (-1.0, 1.0)]
    points = []
    for (a1, b1), (a2, b2) in itertools.combinations(lines, 2):
        M = np.array([a1, a2])
        if abs(np.linalg.det(M)) < 1e-12 * np.abs(M).max() ** 2:
            continue
        p = np.linalg.solve(M, [b1, b2])
        if np.all(np.abs(Lam @ p + mu) <= tau_max * (1.0 + 1e-12)):
            points.append(p)
    return np.array(points)


@pytest.mark.parametrize("kind", ["kinematic", "dynamic", "dynamic_min_norm"])
def test_each_index_equals_an_independent_computation(paper_terms, kind):
    rows = [0, 7, 151, 222, 299]
    terms = _pick(paper_terms, KINEMATIC if kind == "kinematic" else DYNAMIC)
    sub = {k: (v[rows] if k in ("J_u", "P", "xi") else v) for k, v in terms.items()}
    batch = polytope_batch(kind, **sub)
    assert batch.computed.all()
    rng = np.random.default_rng(11)
    directions = rng.normal(size=(6, 2))
    for r in range(len(rows)):
        J = sub["J_u"][r]
        if kind == "kinematic":
            points, centre = _kinematic_polygon(J, sub["W"], sub["velocity_limits"]), np.zeros(2)
            lp = kinematic_lp(J, sub["W"], sub["velocity_limits"])
        elif kind == "dynamic":
            args = (J, sub["W"], sub["P"][r], sub["Q"], sub["xi"][r], sub["M_o"], sub["g_o"], sub["effort_limits"])
            points, centre = _dynamic_polygon(*args)
            lp = dynamic_lp(*args)
        else:  # horizontal motion: mu_o is round-off, the least-effort point solves Lambda_o a = -mu_o
            args = (J, sub["W"], sub["P"][r], sub["Q"], sub["xi"][r], sub["M_o"], sub["g_o"], sub["effort_limits"])
            Lam, mu = policy_map(*args[:-1])
            assert np.linalg.norm(mu) <= 1e-12 * np.linalg.norm(sub["effort_limits"])
            points, centre = _min_norm_polygon(*args), np.linalg.lstsq(Lam, -mu, rcond=None)[0]
            lp = min_norm_lp(*args)
        hull = ConvexHull(points)
        corners = points[hull.vertices]
        size = np.abs(corners).max()
        _assert_volume_and_isotropy(batch, r, hull, centre)
        for d in directions:
            one = np.broadcast_to(d, (len(rows), 2))
            expected = np.max(corners @ d)
            assert batch.support(one)[r] == pytest.approx(expected, rel=1e-12)
            assert batch.support(one)[r] == pytest.approx(lp(d), abs=1e-9 * size * np.linalg.norm(d))  # HiGHS
            u = d / np.linalg.norm(d)
            if np.all(hull.equations[:, 2] < 0):  # the origin inside
                assert batch.straight_line_reach(one)[r] == pytest.approx(_reach(hull, u), rel=1e-12)
        for k, e in enumerate(np.eye(2)):
            width = np.max(corners @ e) - np.min(corners @ e)
            assert batch.widths[r, k] == pytest.approx(width, rel=1e-12)


def test_straight_line_reach_equals_the_reference_program(paper_terms):
    """Through the centre or not: the dynamic set under gravity-free planar motion is centred near,
    not at, the origin; the reference solves one linear program per row."""
    rows = np.arange(0, 300, 30)
    rng = np.random.default_rng(5)
    for kind, names in (("kinematic", KINEMATIC), ("dynamic", DYNAMIC), ("dynamic_min_norm", DYNAMIC)):
        terms = {k: (v[rows] if k in ("J_u", "P", "xi") else v) for k, v in _pick(paper_terms, names).items()}
        fast = polytope_batch(kind, **terms)
        ref = polytope_batch(kind, compiled=False, **terms)
        for _ in range(4):
            d = rng.normal(size=2)
            expected = np.array([ref[i].straight_line_reach(d) for i in range(len(rows))])
            size = np.array([ref[i].circumradius for i in range(len(rows))])
            # HiGHS' optimum, to its feasibility tolerance (1e-7 of the set's size at worst)
            np.testing.assert_allclose(fast.straight_line_reach(d), expected, rtol=0, atol=1e-7 * size.max())


def test_rows_outside_the_generic_case_take_the_reference_path(paper_terms):
    """A flat set (limits zero on the arms' joints, or on all but one torque) is declined by the
    compiled pass and built one at a time: the same flags, zero volume and isotropy. (The
    minimum-norm rows of the 300 with round-off in mu_o take the least-squares centre, as the
    reference does: covered by the comparisons above.)"""
    n = 40
    terms = {k: (v[:n] if k in ("J_u", "P", "xi") else v) for k, v in paper_terms.items()}
    vlim = np.tile(terms["velocity_limits"], (n, 1))
    vlim[::4, 2:] = 0.0  # only the wheels: every hand velocity is the platform's, a segment
    kin = polytope_batch("kinematic", **{**_pick(terms, KINEMATIC), "velocity_limits": vlim})
    ref = polytope_batch("kinematic", compiled=False, **{**_pick(terms, KINEMATIC), "velocity_limits": vlim})
    flat = np.zeros(n, dtype=bool)
    flat[::4] = True
    np.testing.assert_array_equal(kin.computed, ~flat)
    np.testing.assert_array_equal(kin.degenerate, flat)
    np.testing.assert_array_equal(kin.degenerate, ref.degenerate)
    assert np.all(kin.volume[flat] == 0.0) and np.all(kin.isotropy[flat] == 0.0)
    d = np.array([0.3, 1.0])
    np.testing.assert_allclose(kin.support(d), ref.support(d), rtol=1e-12, atol=0)
    assert _rel(kin.volume[~flat], ref.volume[~flat]) <= 1e-12

    tlim = np.tile(terms["effort_limits"], (n, 1))
    tlim[1::5, 1:] = 0.0  # one wheel's torque only: a segment of accelerations
    dyn = polytope_batch("dynamic", **{**_pick(terms, DYNAMIC), "effort_limits": tlim})
    ref = polytope_batch("dynamic", compiled=False, **{**_pick(terms, DYNAMIC), "effort_limits": tlim})
    flat = np.zeros(n, dtype=bool)
    flat[1::5] = True
    np.testing.assert_array_equal(dyn.computed, ~flat)
    np.testing.assert_array_equal(dyn.degenerate, flat)
    np.testing.assert_array_equal(dyn.degenerate, ref.degenerate)
    assert _rel(dyn.volume[~flat], ref.volume[~flat]) <= 1e-12

    # the policy's set with one torque: a segment (or less); the reference decides, as before
    pol = polytope_batch("dynamic_min_norm", **{**_pick(terms, DYNAMIC), "effort_limits": tlim})
    ref = polytope_batch("dynamic_min_norm", compiled=False, **{**_pick(terms, DYNAMIC), "effort_limits": tlim})
    np.testing.assert_array_equal(pol.computed, ~flat)
    np.testing.assert_array_equal(pol.degenerate, ref.degenerate)
    np.testing.assert_array_equal(pol.empty, ref.empty)
    assert pol.degenerate[flat].all()
    assert _rel(pol.volume[~flat], ref.volume[~flat]) <= 1e-12


def test_a_bad_row_raises_as_the_reference_does(paper_terms):
    terms = {k: (v[:5].copy() if k in ("J_u", "P", "xi") else v) for k, v in _pick(paper_terms, DYNAMIC).items()}
    terms["J_u"][3, 0, 0] = np.nan
    for compiled in (True, False):
        with pytest.raises(ModelError, match="J_u has a non-finite entry"):
            polytope_batch("dynamic", compiled=compiled, **terms)


def test_a_planar_sweep_uses_the_compiled_batch_and_keeps_its_indices():
    """The sweep's polytope indices with the compiled batch equal those built one at a time."""
    from mobmanip.sets import capacity
    from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep

    grid = SweepGrid(angle_deg=np.linspace(0.0, 330.0, 12), distance=[0.8, 1.1], heading_deg=[0.0, 40.0])
    polytopes = ("kinematic_polytope", "dynamic_polytope", "dynamic_polytope_min_norm")
    spec = SweepSpec("planar_dual_arm", measures=polytopes, decoupled=True)
    fast = run_sweep(spec, grid, workers=1)
    original = capacity.polytope_batch
    try:
        capacity.polytope_batch = lambda kind, **terms: original(kind, compiled=False, **terms)  # type: ignore[assignment]
        slow = run_sweep(spec, grid, workers=1)
    finally:
        capacity.polytope_batch = original
    assert fast.reachable.all()
    for name in polytopes:
        for index in ("volume", "isotropy", "capacity", "width_1", "width_2"):
            a, b = fast.index(f"{name}.{index}"), slow.index(f"{name}.{index}")
            assert _rel(a, b) <= 1e-12, (name, index)


# --------------------------------------------------------------------------- 3-D zonotopes


@pytest.fixture(scope="module")
def tiago_terms():
    """TIAGo++ holding 2 kg at 200 random joint configurations, translational task (m = 3)."""

    robot = mobmanip.load_robot("tiago_dual")
    rng = np.random.default_rng(9)
    return stacked_terms(
        [terms_at(robot, configuration_within_limits(robot, rng), "translational", object_mass=2.0) for _ in range(200)]
    )


def test_3d_exact_dynamic_batch_equals_one_polytope_per_configuration(tiago_terms):
    terms = _pick(tiago_terms, DYNAMIC)
    fast = polytope_batch("dynamic", **terms)
    ref = polytope_batch("dynamic", compiled=False, **terms)
    assert isinstance(fast, CompiledPolytopeBatch) and fast.dim == 3 and fast.computed.all()
    d = np.random.default_rng(4).normal(size=(len(ref), 3))
    np.testing.assert_array_equal(fast.degenerate, ref.degenerate)
    assert _rel(fast.volume, ref.volume) <= 1e-12
    assert _rel(fast.isotropy, ref.isotropy) <= 1e-12
    assert _rel(fast.support(d), ref.support(d)) <= 1e-12
    assert _rel(fast.radius_along(d), ref.radius_along(d)) <= 1e-12
    assert _rel(fast.widths, ref.widths) <= 1e-12
    rows = range(0, len(ref), 20)
    expected = np.array([ref[i].straight_line_reach(d[i]) for i in rows])
    size = max(ref[i].circumradius for i in rows)
    # HiGHS' optimum, to its feasibility tolerance (1e-7 of the set's size at worst)
    np.testing.assert_allclose(fast.straight_line_reach(d)[list(rows)], expected, rtol=0, atol=1e-7 * size)


def test_3d_indices_equal_the_hull_of_the_torque_corners(tiago_terms):
    """Volume, isotropy, support and widths of TIAGo++'s exact dynamic set (under gravity: its
    centre is off the origin) against Qhull's hull of the accelerations at all 2^16 torque
    corners, each from the defining equations solved densely."""
    rows = [0, 50, 199]
    sub = {k: (v[rows] if k in ("J_u", "P", "xi") else v) for k, v in _pick(tiago_terms, DYNAMIC).items()}
    batch = polytope_batch("dynamic", **sub)
    assert batch.computed.all()
    nx = sub["J_u"].shape[2]
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=nx)))
    d = np.random.default_rng(2).normal(size=(5, 3))
    for r in range(len(rows)):
        args = (sub["J_u"][r], sub["W"], sub["P"][r], sub["Q"], sub["xi"][r], sub["M_o"], sub["g_o"])
        # the acceleration is affine in the torques: a = a0 + B tau, B's columns from unit torques
        unit = [_dynamic_point(*args, tau) for tau in np.vstack([np.zeros(nx), np.eye(nx)])]
        a0, B = unit[0], np.array(unit[1:]).T - unit[0][:, None]
        corners = a0 + (signs * sub["effort_limits"]) @ B.T
        hull = ConvexHull(corners)
        V = corners[hull.vertices]
        _assert_volume_and_isotropy(batch, r, hull, a0)
        for direction in d:
            one = np.broadcast_to(direction, (len(rows), 3))
            assert batch.support(one)[r] == pytest.approx(np.max(V @ direction), rel=1e-12)
        for k, e in enumerate(np.eye(3)):
            assert batch.widths[r, k] == pytest.approx(np.max(V @ e) - np.min(V @ e), rel=1e-12)


def test_3d_kinematic_sections_stay_on_the_reference_path(tiago_terms):
    """Two hands: a section of a 6-D zonotope, whose 3-D facets need a hull (the reference's Qhull)."""
    terms = {k: (v[:6] if k in ("J_u", "P", "xi") else v) for k, v in _pick(tiago_terms, KINEMATIC).items()}
    fast = polytope_batch("kinematic", **terms)
    ref = polytope_batch("kinematic", compiled=False, **terms)
    assert not fast.computed.any()
    np.testing.assert_array_equal(fast.volume, ref.volume)


@pytest.mark.parametrize("task", ["planar", "translational"])
def test_one_hand_kinematic_zonotopes(task):
    """One hand (W = I): the kinematic set is the zonotope J_u box, compiled in 2-D and 3-D; its
    volume and support equal the hull of its 2^n corners."""

    robot = mobmanip.load_robot("panda")
    rng = np.random.default_rng(12)
    rows = [terms_at(robot, configuration_within_limits(robot, rng), task) for _ in range(100)]
    terms = {"J_u": np.stack([t.J_u for t in rows]), "W": rows[0].W, "velocity_limits": rows[0].velocity_limits}
    fast = polytope_batch("kinematic", **terms)
    ref = polytope_batch("kinematic", compiled=False, **terms)
    m = rows[0].W.shape[0]
    assert fast.dim == m and fast.computed.all()
    d = rng.normal(size=(100, m))
    for a, b in (
        (fast.volume, ref.volume),
        (fast.isotropy, ref.isotropy),
        (fast.support(d), ref.support(d)),
        (fast.widths, ref.widths),
    ):
        assert _rel(a, b) <= 1e-12
    n = terms["J_u"].shape[2]
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=n)))
    for r in (0, 99):
        corners = (signs * terms["velocity_limits"]) @ terms["J_u"][r].T
        hull = ConvexHull(corners)
        assert fast.volume[r] == pytest.approx(hull.volume, rel=1e-12)
        assert fast.support(d)[r] == pytest.approx(np.max(corners @ d[r]), rel=1e-12)


def test_parallelograms_are_compiled_too():
    """Two joints, one hand: the set is the parallelogram J diag(lim) [-1, 1]^2, area 4 |det J| lim_1 lim_2,
    its inradius the smaller half-height over its farthest corner."""
    rng = np.random.default_rng(1)
    J, lim = rng.normal(size=(50, 2, 2)), np.array([1.0, 2.0])
    batch = polytope_batch("kinematic", J_u=J, W=np.eye(2), velocity_limits=lim)
    assert batch.computed.all()
    G = J * lim
    np.testing.assert_allclose(batch.volume, 4.0 * np.abs(np.linalg.det(G)), rtol=1e-12)
    area = 4.0 * np.abs(np.linalg.det(G))
    heights = area[:, None] / (2.0 * np.linalg.norm(G, axis=1))  # distance between each pair of sides
    corners = np.stack([G[:, :, 0] + G[:, :, 1], G[:, :, 0] - G[:, :, 1]], axis=1)
    far = np.linalg.norm(corners, axis=2).max(axis=1)
    np.testing.assert_allclose(batch.isotropy, heights.min(axis=1) / 2.0 / far, rtol=1e-12)


def test_nearly_flat_sets_are_left_to_the_reference():
    """Generators whose smallest singular value is 1e-12 (flat for the reference) or 3e-9 (not
    flat, but within the kernel's margin) of the largest: both rows are built one at a time."""
    J = np.array([[[1.0, 2.0], [1.0, 2.0 + 1e-11]], [[1.0, 2.0], [1.0, 2.0 + 3e-8]], [[1.0, 0.0], [0.0, 1.0]]])
    s = np.linalg.svd(J, compute_uv=False)
    assert s[0, 1] / s[0, 0] < 1e-10 < 1e-9 < s[1, 1] / s[1, 0] < 1e-6
    fast = polytope_batch("kinematic", J_u=J, W=np.eye(2), velocity_limits=np.ones(2))
    ref = polytope_batch("kinematic", compiled=False, J_u=J, W=np.eye(2), velocity_limits=np.ones(2))
    np.testing.assert_array_equal(fast.computed, [False, False, True])
    np.testing.assert_array_equal(fast.degenerate, [True, False, False])
    np.testing.assert_array_equal(fast.degenerate, ref.degenerate)
    np.testing.assert_array_equal(fast.volume[:2], ref.volume[:2])
    assert fast.volume[2] == pytest.approx(4.0, rel=1e-15)  # the unit square, side 2


def test_stacked_terms_stack_what_changes_and_refuse_rows_of_different_batches():
    import dataclasses

    from mobmanip.errors import TaskError

    robot = mobmanip.load_robot("planar_dual_arm")
    rng = np.random.default_rng(8)
    rows = [terms_at(robot, configuration_within_limits(robot, rng), "planar", object_mass=2.0) for _ in range(3)]
    terms = stacked_terms(rows)
    for i, row in enumerate(rows):
        for name in ("J_u", "P", "xi"):
            assert np.array_equal(terms[name][i], getattr(row, name))
    for name in ("W", "Q", "M_o", "g_o", "velocity_limits", "effort_limits"):
        assert np.array_equal(terms[name], getattr(rows[0], name))
    heavier = dataclasses.replace(rows[2], M_o=2.0 * rows[2].M_o)  # a heavier object
    with pytest.raises(TaskError, match="M_o of row 2 differs from row 0's"):
        stacked_terms([*rows[:2], heavier])
    with pytest.raises(TaskError, match="needs at least one"):
        stacked_terms([])
