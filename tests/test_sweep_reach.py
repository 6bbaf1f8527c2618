"""The sweeps' straight-line reach: the largest s >= 0 with s d in the set, d the sweep's unit
direction, beside its support (the ``capacity`` index, max d . p over the set).

Each polytope's reach is checked against a linear program written here from the set's defining
equations (the joint box, the closed chain, the grasp) with the point pinned to the ray s d and s
maximised, on HiGHS; each ellipsoid's against bisection on a membership test. The properties: the
reach never exceeds the support (s d in the set gives d . (s d) = s); where the set is centred
at the origin and mirror-symmetric about the ray's line (the paper robot with the object straight
ahead) they are equal; where gravity shifts the set (a vertical task) they differ.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import mobmanip
from mobmanip.batch import EllipsoidBatch
from mobmanip.sets.capacity import polytope_batch
from mobmanip.sets.ellipsoid import Ellipsoid, dynamic_ellipsoid, kinematic_ellipsoid
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep, sweep_configurations
from mobmanip.terms.builder import terms_at
from mobmanip.viz.sweep_plot import index_label
from polytope_util import policy_map

POLYTOPES = ("kinematic_polytope", "dynamic_polytope", "dynamic_polytope_min_norm")
ELLIPSOIDS = ("kinematic", "dynamic")
TIGHT = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


# --------------------------------------------------------------------------- references


def _ray_program(A_var: np.ndarray, A_point: np.ndarray, b: np.ndarray, bounds: list, d: np.ndarray) -> float:
    """max s over (s, z) subject to A_point (s d) + A_var z = b, z within ``bounds``, s >= 0;
    0 when no s is feasible (the ray misses the set)."""
    A = np.hstack([(A_point @ d)[:, None], A_var])
    cost = np.zeros(A.shape[1])
    cost[0] = -1.0
    result = linprog(cost, A_eq=A, b_eq=b, bounds=[(0.0, None)] + bounds, method="highs", options=TIGHT)
    assert result.status in (0, 2), result.message
    return float(result.x[0]) if result.status == 0 else 0.0


def kinematic_reach(t, d) -> float:
    """Object velocities s d with W^T (s d) = J_u x, |x_i| <= xdot_max_i."""
    return _ray_program(-t.J_u, t.W.T, np.zeros(t.J_u.shape[0]), [(-v, v) for v in t.velocity_limits], d)


def dynamic_reach(t, d) -> float:
    """Object accelerations s d of the exact set: over (qdd, tau, h), P qdd - Q tau + J_u^T h = xi,
    J_u qdd = W^T (s d), W h = M_o (s d) + g_o, |tau_i| <= tau_max_i."""
    mk, n = t.J_u.shape
    m = t.W.shape[0]
    A = np.zeros((n + mk + m, 2 * n + mk))
    P_a = np.zeros((n + mk + m, m))
    A[:n, :n], A[:n, n : 2 * n], A[:n, 2 * n :] = t.P, -t.Q, t.J_u.T
    A[n : n + mk, :n], P_a[n : n + mk] = t.J_u, -t.W.T
    A[n + mk :, 2 * n :], P_a[n + mk :] = t.W, -t.M_o
    b = np.r_[t.xi, np.zeros(mk), t.g_o]
    free = [(None, None)] * n
    return _ray_program(A, P_a, b, free + [(-e, e) for e in t.effort_limits] + [(None, None)] * mk, d)


def min_norm_reach(t, d) -> float:
    """The policy's set: tau = Lambda_o (s d) + mu_o within the effort box."""
    Lam, mu = policy_map(t.J_u, t.W, t.P, t.Q, t.xi, t.M_o, t.g_o)
    n = Lam.shape[0]
    return _ray_program(np.eye(n), -Lam, mu, [(-e, e) for e in t.effort_limits], d)


REFERENCE = {
    "kinematic_polytope": kinematic_reach,
    "dynamic_polytope": dynamic_reach,
    "dynamic_polytope_min_norm": min_norm_reach,
}


def bisected_reach(inside, u: np.ndarray, radius: float, samples: int = 4001) -> float:
    """The largest s in [0, radius] with ``inside(s u)``, by a scan for the last inside sample and
    bisection past it (0 when no sample is inside)."""
    s = np.linspace(0.0, radius, samples)
    hits = np.flatnonzero([inside(v * u) for v in s])
    if hits.size == 0:
        return 0.0
    lo = s[hits[-1]]
    hi = s[min(hits[-1] + 1, samples - 1)] if hits[-1] + 1 < samples else radius
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if inside(mid * u) else (lo, mid)
    return lo


def _ellipsoid_reach(e: Ellipsoid, u: np.ndarray) -> float:
    radius = 1.01 * (np.linalg.norm(e.center) + e.semi_axes[0])  # every point farther is outside
    return bisected_reach(lambda p: e.contains(p, tol=0.0), u, radius)


def _ellipsoid_at(name: str, t) -> Ellipsoid:
    if name == "kinematic":
        return kinematic_ellipsoid(t.J_u, t.W, t.velocity_limits)
    return dynamic_ellipsoid(t.J_u, t.W, t.P, t.Q, t.xi, t.M_o, t.g_o, t.effort_limits)


# --------------------------------------------------------------------------- sweeps


@pytest.fixture(scope="module")
def paper_sweep():
    grid = SweepGrid(angle_deg=np.linspace(0.0, 345.0, 24), distance=[0.8, 1.2])
    spec = SweepSpec("planar_dual_arm", measures=ELLIPSOIDS + POLYTOPES, decoupled=True, object_mass=2.0)
    return run_sweep(spec, grid, workers=1)


def _configurations(result):
    robot = mobmanip.load_robot(str(result.spec.robot))
    flat = np.arange(result.grid.n_configurations)
    qs, reachable = sweep_configurations(robot, result.grid, result.postures, flat)
    return robot, qs, reachable


def _sweep_direction(result, flat: int) -> np.ndarray:
    ia, _, ih = np.unravel_index(flat, result.grid.shape[:3])
    if isinstance(result.spec.direction, str):
        phi = np.radians(result.grid.angle_deg[ia] + result.grid.heading_deg[ih])
        return np.array([np.cos(phi), np.sin(phi)])
    d = np.asarray(result.spec.direction, dtype=float)
    return d / np.linalg.norm(d)


def _column(result, name: str, index: str) -> np.ndarray:
    return result.index(f"{name}.{index}")[..., 0, 0].reshape(-1)


def _check_against_references(result, task: str, rows) -> int:
    robot, qs, reachable = _configurations(result)
    checked = 0
    for i in rows:
        if not reachable[i]:
            continue
        t = terms_at(robot, qs[i], task, object_mass=2.0, decoupled=result.spec.decoupled)
        d = _sweep_direction(result, i)
        for name in POLYTOPES:
            if name in result.spec.measures:
                got, expected = _column(result, name, "straight_line_reach")[i], REFERENCE[name](t, d)
                assert got == pytest.approx(expected, rel=1e-9, abs=1e-12), (name, i)
        for name in ELLIPSOIDS:
            if name in result.spec.measures:
                e = _ellipsoid_at(name, t)
                got, expected = _column(result, name, "straight_line_reach")[i], _ellipsoid_reach(e, d)
                assert got == pytest.approx(expected, rel=1e-9, abs=1e-12), (name, i)
        checked += 1
    return checked


def test_planar_sweep_reach_equals_the_programs_and_bisection(paper_sweep):
    assert _check_against_references(paper_sweep, "planar", range(0, 48, 5)) == 10


def test_reach_never_exceeds_the_support_and_equals_it_on_a_mirror_line(paper_sweep):
    """With the object straight ahead (0 deg) or behind (180 deg) the paper robot is mirror-symmetric
    about the radial line and its planar sets are centred at the origin (no gravity in the plane):
    the points farthest along d lie on the ray, so the reach is the support. Elsewhere the
    polytopes' corners leave the ray and the reach is smaller somewhere."""
    angle = np.repeat(paper_sweep.grid.angle_deg, len(paper_sweep.grid.distance))
    mirror = np.isin(angle, (0.0, 180.0))
    assert mirror.sum() == 4
    for name in ELLIPSOIDS + POLYTOPES:
        reach, support = _column(paper_sweep, name, "straight_line_reach"), _column(paper_sweep, name, "capacity")
        assert np.all(np.isfinite(reach)) and np.all(reach > 0.0), name
        assert np.all(reach <= support * (1.0 + 1e-12)), name
        np.testing.assert_allclose(reach[mirror], support[mirror], rtol=1e-9, err_msg=name)
        if name in POLYTOPES:
            assert np.any(reach < support * (1.0 - 1e-3)), name


def test_gravity_makes_reach_and_support_differ():
    """TIAGo++ holding 2 kg, translational task, directions up, down and slanted: gravity shifts
    the acceleration sets down, so the reach is short of the support, and each equals its
    independent reference. The paper's dynamic ellipsoid lies wholly below the origin here (its
    support upward is negative): no point of the upward ray is in it, and its reach is 0."""
    grid = SweepGrid(angle_deg=[-20.0, 20.0], distance=[0.5])
    measures = ("dynamic", "dynamic_polytope", "kinematic_polytope")
    for direction in ((0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (0.6, 0.0, 0.8)):
        spec = SweepSpec("tiago_dual", task="translational", measures=measures, direction=direction, object_mass=2.0)
        result = run_sweep(spec, grid, workers=1)
        assert result.reachable.all()
        assert _check_against_references(result, "translational", range(2)) == 2
        for name in measures:
            reach, support = _column(result, name, "straight_line_reach"), _column(result, name, "capacity")
            assert np.all(reach <= np.maximum(support, 0.0) * (1.0 + 1e-12)), (name, direction)
        reach = {name: _column(result, name, "straight_line_reach") for name in measures}
        support = {name: _column(result, name, "capacity") for name in measures}
        if direction[2] == 1.0:
            assert np.all(reach["dynamic_polytope"] < support["dynamic_polytope"] - 1.0)
            assert np.all(support["dynamic"] < 0.0) and np.all(reach["dynamic"] == 0.0)
        if direction[2] == -1.0:
            for name in ("dynamic", "dynamic_polytope"):
                assert np.all(reach[name] < support[name] - 1.0), name


def test_reach_is_a_sweep_index_everywhere(paper_sweep, tmp_path):
    """In the names users ask for, the NPZ arrays and the CSV columns, with the same values."""
    import csv

    from mobmanip.commands.outputs import write_sweep_csv, write_sweep_npz
    from mobmanip.sweep.results import index_names

    names = index_names(2, paper_sweep.spec.measures)
    npz = np.load(write_sweep_npz(paper_sweep, tmp_path / "s.npz"))
    with open(write_sweep_csv(paper_sweep, tmp_path / "s.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    for name in ELLIPSOIDS + POLYTOPES:
        assert f"{name}.straight_line_reach" in names
        values = paper_sweep.index(f"{name}.straight_line_reach")
        np.testing.assert_array_equal(npz[f"{name}_straight_line_reach"], values)
        column = np.array([float(r[f"{name}_straight_line_reach"]) for r in rows])
        np.testing.assert_allclose(column, values.ravel(), rtol=1e-11)  # written to 12 digits
    label = index_label("dynamic_polytope.straight_line_reach", "planar")
    assert label == "dynamic polytope straight-line reach (m/s$^2$)"


def _no_set(terms):
    raise AssertionError("only the batch form is used here")


def _empty_batch(request):
    (name,) = request.limits
    out = EllipsoidBatch.allocate(len(request.terms), request.setup.m)
    out.axes[:] = np.eye(request.setup.m)
    out.empty[::2] = True  # every other configuration empty, the others a unit disc at the origin
    out.semi_axes[~out.empty] = 1.0
    return {name: out}


def test_empty_sets_record_nan():
    """A sweep records NaN for the reach and the support of an empty set (never 0 or infinity),
    while its batch answers 0 as for every query on an empty set."""
    from mobmanip import Measure, register_measure, unregister_measure
    from mobmanip.measures import VELOCITY

    # name, JSON key, quantity, label, set kind, colour, locked colour, compute (never called), batch form
    measure = Measure("half_empty", "half_empty", VELOCITY, "half-empty disc", "ellipsoid", 0x123456, 0x654321,
                      _no_set, batch=_empty_batch)  # fmt: skip
    register_measure(measure)
    try:
        grid = SweepGrid(angle_deg=[0.0, 90.0], distance=[1.0])
        result = run_sweep(SweepSpec("planar_dual_arm", measures=("half_empty",)), grid, workers=1)
        reach = result.index("half_empty.straight_line_reach").ravel()
        support = result.index("half_empty.capacity").ravel()
    finally:
        unregister_measure("half_empty")
    empty = result.indices["half_empty_empty"].ravel()
    assert empty.tolist() == [True, False]
    assert np.isnan(reach[0]) and np.isnan(support[0])
    assert reach[1] == pytest.approx(1.0, rel=1e-15) and support[1] == pytest.approx(1.0, rel=1e-15)
    batch = EllipsoidBatch.allocate(2, 2)
    batch.axes[:], batch.semi_axes[1], batch.empty[0] = np.eye(2), 1.0, True
    assert batch.straight_line_reach(np.array([1.0, 0.0])).tolist() == [0.0, 1.0]


# --------------------------------------------------------------------------- the batches


def _paper_terms(count: int, seed: int) -> dict:
    from conftest import random_configurations

    robot = mobmanip.load_robot("planar_dual_arm")
    qs = random_configurations(robot, np.random.default_rng(seed), count)
    rows = [terms_at(robot, q, "planar", object_mass=2.0) for q in qs]
    stacked = {k: np.stack([getattr(t, k) for t in rows]) for k in ("J_u", "P", "xi")}
    shared = {k: getattr(rows[0], k) for k in ("W", "Q", "M_o", "g_o", "velocity_limits", "effort_limits")}
    return {**stacked, **shared, "rows": rows}


@pytest.mark.parametrize("kind", ["kinematic", "dynamic", "dynamic_min_norm"])
def test_compiled_and_per_configuration_batches_agree(kind):
    """The compiled batch intersects the ray with each polygon's facets, the per-configuration one
    solves a program per row; both against the reference program of this file."""
    terms = _paper_terms(40, 11)
    rows = terms.pop("rows")
    if kind == "kinematic":
        terms = {k: terms[k] for k in ("J_u", "W", "velocity_limits")}
    else:
        terms.pop("velocity_limits")
    fast = polytope_batch(kind, **terms)
    slow = polytope_batch(kind, compiled=False, **terms)
    assert fast.computed.sum() > 30  # the compiled route is what is compared
    rng = np.random.default_rng(2)
    D = rng.normal(size=(len(rows), 2))
    a, b = fast.straight_line_reach(D), slow.straight_line_reach(D)
    reference = {"kinematic": kinematic_reach, "dynamic": dynamic_reach, "dynamic_min_norm": min_norm_reach}[kind]
    expected = np.array([reference(t, d / np.linalg.norm(d)) for t, d in zip(rows, D)])
    np.testing.assert_allclose(a, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("m, flat", [(2, False), (3, False), (3, True), (4, False)])
def test_polytope_reach_by_facets_or_program_equals_the_reference(m, flat):
    """Random sections {a : F a in c + G [-1, 1]^n} around, off and far from the origin: full
    sets of up to 3 dimensions are cut by their facets, flat and 4-D ones solve a program; both
    equal the reference program over (s, y): F (s u) - G y = c."""
    from mobmanip.sets.polytope import Polytope

    rng = np.random.default_rng(10 * m + flat)
    crossing = 0
    for k in range(40):
        p, n = m + 1, m + 4
        F = rng.normal(size=(p, m))
        G = rng.normal(size=(p, n))
        if flat:  # the set lies in a plane: G and F share a (p - 1)-dimensional range
            basis = np.linalg.qr(rng.normal(size=(p, p - 1)))[0]
            G = basis @ basis.T @ G
            F = np.hstack([basis[:, :2], rng.normal(size=(p, 1))])
        u = rng.normal(size=m)
        if flat and k % 2:  # along the set's plane through the origin, {a : F a in range(basis)}
            normal = F.T @ np.linalg.svd(basis.T)[2][-1]
            u -= (u @ normal) / (normal @ normal) * normal
        u /= np.linalg.norm(u)
        c = (0.0, 1.5, -1.5, 4.0)[k % 4] * F @ u + 0.2 * rng.normal(size=p)
        if flat:
            c = basis @ basis.T @ c
        P = Polytope(F, c, G)
        if P.empty:
            continue
        assert P.degenerate == flat
        expected = _ray_program(-G, F, c, [(-1.0, 1.0)] * n, u)
        assert P.straight_line_reach(u) == pytest.approx(expected, rel=1e-9, abs=1e-12), k
        crossing += expected > 0.0
    assert crossing > 10


# --------------------------------------------------------------------------- ellipsoids alone


def _inside_by_definition(c, G):
    """p is in {c + G z : |z| <= 1}, G square and invertible: |G^-1 (p - c)| <= 1."""
    G_inv = np.linalg.inv(G)
    return lambda p: float(np.linalg.norm(G_inv @ (p - c))) <= 1.0


@pytest.mark.parametrize("m", [2, 3, 6])
def test_ellipsoid_reach_equals_bisection_on_the_definition(m):
    """Random ellipsoids around, off and far from the origin: origin inside, origin outside with
    the ray crossing the set (the far crossing counts), and the ray missing it (0)."""
    rng = np.random.default_rng(m)
    cases = 0
    for k in range(60):
        G = rng.normal(size=(m, m))
        u = rng.normal(size=m)
        u /= np.linalg.norm(u)
        shift = (0.3, 2.0, -2.0)[k % 3] * np.linalg.norm(G, 2)
        c = shift * u + 0.2 * rng.normal(size=m)
        e = Ellipsoid.from_generator(c, G)
        radius = 1.01 * (np.linalg.norm(c) + np.linalg.norm(G, 2))
        expected = bisected_reach(_inside_by_definition(c, G), u, radius)
        got = e.straight_line_reach(u)
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-12), k
        batch = EllipsoidBatch(
            e.center[None], e.semi_axes[None], e.axes[None], e.matrix[None], np.array([False]), np.array([False])
        )
        assert batch.straight_line_reach(3.0 * u)[0] == pytest.approx(got, rel=1e-14)  # any length of d
        assert got <= max(e.support(u), 0.0) * (1.0 + 1e-12)  # 0 where the ray misses
        cases += expected > 0.0
    assert 20 < cases < 60  # both rays that cross and rays that miss were drawn


def test_flat_and_empty_ellipsoids():
    """A disc in 3-D centred at the origin: along a direction in its plane the reach is the
    definition's 1 / |G^+ d|; across the plane only the origin is on the ray (0). An empty set: 0."""
    rng = np.random.default_rng(4)
    G = np.zeros((3, 3))
    G[:, :2] = rng.normal(size=(3, 2))
    e = Ellipsoid.from_generator(np.zeros(3), G)
    assert e.degenerate
    u = G[:, :2] @ rng.normal(size=2)
    u /= np.linalg.norm(u)
    assert e.straight_line_reach(u) == pytest.approx(1.0 / np.linalg.norm(np.linalg.pinv(G) @ u), rel=1e-9)
    normal = np.cross(G[:, 0], G[:, 1])
    assert e.straight_line_reach(normal + 0.3 * u) == 0.0
    # the disc lifted to 2 along its normal n: a ray crossing the plane meets it at s = 2 / (u . n)
    n = normal / np.linalg.norm(normal)
    lifted = Ellipsoid.from_generator(2.0 * n, G)
    for lean in (0.05, 3.0):  # the crossing inside the disc, then far outside it
        d = n + lean * u
        d /= np.linalg.norm(d)
        s = 2.0 / (d @ n)
        inside = np.linalg.norm(np.linalg.pinv(G) @ (s * d - 2.0 * n)) <= 1.0
        assert lifted.straight_line_reach(d) == (pytest.approx(s, rel=1e-12) if inside else 0.0), lean
    empty = Ellipsoid.from_generator(np.ones(3), np.eye(3), empty=True)
    assert empty.straight_line_reach(np.ones(3)) == 0.0


def test_a_shifted_disc_by_hand():
    """The unit disc centred at (2, 0). Along +x the ray crosses it from s = 1 to s = 3: the reach
    is 3 (the support too). At angle t the ray passes the centre at distance 2 sin t: at 20 deg it
    crosses the disc up to s = 2 cos t + sqrt(1 - 4 sin^2 t); at 45 deg and along -x it misses."""
    e = Ellipsoid.from_generator(np.array([2.0, 0.0]), np.eye(2))
    assert e.straight_line_reach(np.array([1.0, 0.0])) == pytest.approx(3.0, rel=1e-15)
    t = np.radians(20.0)
    expected = 2.0 * np.cos(t) + np.sqrt(1.0 - 4.0 * np.sin(t) ** 2)
    assert e.straight_line_reach(np.array([np.cos(t), np.sin(t)])) == pytest.approx(expected, rel=1e-14)
    assert e.straight_line_reach(np.array([1.0, 1.0])) == 0.0
    assert e.straight_line_reach(np.array([-1.0, 0.0])) == 0.0
