"""The exact capacity polytopes of real robots, checked against independent mathematics.

References, none of which calls the polytope code:

* linear programs over the joint box written from the defining equations (qdd, tau, h and a_o
  as variables for the dynamic set; x and v_o for the kinematic one), on HiGHS;
* pycapacity's velocity and acceleration polytopes of one fixed-base arm;
* the paper's ellipsoids (ball inside box inside sqrt(n) ball);
* Pinocchio: joint velocities pushed through forward kinematics, torques through ABA with the
  object's wrench on the hands (tests/polytope_util.py).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import mobmanip
from conftest import configuration_within_limits, paper_case, random_configuration
from mobmanip.sets.capacity import dynamic_polytope, kinematic_polytope, min_norm_dynamic_polytope
from mobmanip.sets.ellipsoid import dynamic_ellipsoid
from polytope_util import (
    closed_chain_acceleration,
    dynamic_lp,
    dynamic_terms,
    hand_velocities,
    kinematic_lp,
    min_norm_lp,
    policy_map,
    terms,
)

SUPPORT_RTOL = 1e-7  # the bound; round-off here is ~1e-13
DIRECTIONS = 1000


@pytest.fixture(scope="module")
def paper():
    return paper_case(45.0)


@pytest.fixture(scope="module")
def tiago():
    robot = mobmanip.load_robot("tiago_dual")
    return robot, robot.hold_configuration()


def _unit(rng, count, dim):
    d = rng.normal(size=(count, dim))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _assert_supports(poly, lp, directions):
    ours = poly.supports(directions)
    ref = np.array([lp(d) for d in directions])
    scale = np.maximum(np.abs(ref), 1e-3 * np.abs(ref).max())
    err = np.abs(ours - ref) / scale
    assert err.max() <= SUPPORT_RTOL, (err.max(), int(err.argmax()))


# ---------------------------------------------------------------------------------------------
# Support functions against linear programs over the joint box

CASES = [
    ("paper", "planar", "mobile", None),
    ("paper", "planar", "fixed", None),
    ("tiago", "translational", "mobile", 0.0),
    ("tiago", "translational", "mobile", 3.0),
    ("tiago", "translational", "fixed", 3.0),
    ("tiago", "spatial", "mobile", 0.0),
    ("tiago", "spatial", "mobile", 3.0),
    ("tiago", "spatial", "fixed", 0.0),
    ("tiago", "spatial", "fixed", 3.0),
]


@pytest.mark.parametrize("name, task, platform, mass", CASES)
def test_supports_equal_joint_box_linear_programs(request, rng, name, task, platform, mass):
    robot, q = request.getfixturevalue(name)
    if platform == "fixed":
        robot = robot.with_platform("fixed")
    _, t = terms(robot, q, task, mass)
    m = t["W"].shape[0]
    directions = _unit(rng, DIRECTIONS, m)
    kin = kinematic_polytope(t["J_u"], t["W"], t["velocity_limits"])
    _assert_supports(kin, kinematic_lp(t["J_u"], t["W"], t["velocity_limits"]), directions)
    dyn = dynamic_polytope(**dynamic_terms(t))
    _assert_supports(dyn, dynamic_lp(*dynamic_terms(t).values()), directions)
    policy = min_norm_dynamic_polytope(**dynamic_terms(t))
    _assert_supports(policy, min_norm_lp(*dynamic_terms(t).values()), directions[:200])


def test_gravity_load_shifts_the_dynamic_set_by_the_load_alone(tiago, rng):
    """With and without a load the exact sets differ, and each matches its own program: the
    load is really in the numbers (not a test that passes for any mass)."""
    robot, q = tiago
    heavy_terms = terms(robot, q, "translational", 3.0)[1]
    light = dynamic_polytope(**dynamic_terms(terms(robot, q, "translational", 0.0)[1]))
    heavy = dynamic_polytope(**dynamic_terms(heavy_terms))
    up = np.array([0.0, 0.0, 1.0])
    assert heavy.support(up) < light.support(up) - 0.1  # a 3 kg load costs upward acceleration
    # the wrench that holds the load points up (the model's gravity points down)
    assert robot.model.gravity.linear[2] < 0
    np.testing.assert_allclose(heavy_terms["g_o"], -3.0 * robot.model.gravity.linear, rtol=1e-12)
    # and the set matches the exact LP (tests/polytope_util.py, written from the equations with
    # W h = M_o a_o + g_o) along and against gravity: a sign flipped inside the set's
    # construction moves its supports by several m/s^2
    lp = dynamic_lp(*dynamic_terms(heavy_terms).values())
    for d in (up, -up):
        assert heavy.support(d) == pytest.approx(lp(d), rel=1e-6, abs=1e-6)


# ---------------------------------------------------------------------------------------------
# pycapacity, one fixed-base arm without object


def _match_vertices(ours, theirs):
    """Largest distance from each of our vertices to theirs and back (sets of points)."""
    d = np.linalg.norm(ours[:, None, :] - theirs[None, :, :], axis=2)
    return max(d.min(axis=1).max(), d.min(axis=0).max())


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_vertices_agree_with_pycapacity(name, rng):
    from pycapacity.robot import acceleration_polytope, velocity_polytope

    robot = mobmanip.load_robot(name)
    for _ in range(3):
        q = configuration_within_limits(robot, rng)
        _, t = terms(robot, q, "translational", 0.0)
        J, vlim, tlim = t["J_u"], t["velocity_limits"], t["effort_limits"]
        kin = kinematic_polytope(J, t["W"], vlim)
        ref = velocity_polytope(J, vlim, -vlim).vertices.T
        assert len(kin.vertices) == len(ref)
        assert _match_vertices(kin.vertices, ref) <= 1e-7 * np.abs(ref).max()
        dyn = dynamic_polytope(**dynamic_terms(t))
        ref = acceleration_polytope(J, t["P"], tlim, -tlim, t_bias=-t["xi"]).vertices.T
        assert len(dyn.vertices) == len(ref)
        assert _match_vertices(dyn.vertices, ref) <= 1e-7 * np.abs(ref).max()


def test_square_arm_policy_set_is_the_exact_set(rng):
    """UR5, spatial task, one hand: J is square, so the minimum-norm choice is the only choice
    and the paper's policy set equals the exact dynamic set, built two different ways."""
    robot = mobmanip.load_robot("ur5")
    q = configuration_within_limits(robot, rng)
    _, t = terms(robot, q, "spatial", 2.0)
    exact = dynamic_polytope(**dynamic_terms(t))
    policy = min_norm_dynamic_polytope(**dynamic_terms(t))
    d = _unit(rng, 100, 6)
    ref = exact.supports(d)
    np.testing.assert_allclose(policy.supports(d), ref, rtol=0, atol=1e-9 * np.abs(ref).max())


# ---------------------------------------------------------------------------------------------
# Ellipsoids inside polytopes


def _facets_hold(poly, ell, scale=1.0):
    """Every halfspace of the polytope holds on the ellipsoid scaled about its centre."""
    A, b = poly.halfspaces
    h = A @ ell.center + scale * np.linalg.norm(A @ ell.generator, axis=1)
    return np.all(h <= b + 1e-9 * np.abs(b).max())


def _vertices_in(ell, vertices, scale):
    """Every vertex lies in the ellipsoid scaled by ``scale`` about its centre."""
    return bool(np.all(ell.contains(ell.center + (vertices - ell.center) / scale, tol=1e-9)))


@pytest.mark.parametrize("name, task, count", [("paper", "planar", 200), ("tiago", "translational", 100)])
def test_kinematic_ellipsoid_inside_polytope_inside_sqrt_n_ellipsoid(request, rng, name, task, count):
    robot, _ = request.getfixturevalue(name)
    ratios = []
    for _ in range(count):
        q = random_configuration(robot, rng) if name == "paper" else configuration_within_limits(robot, rng)
        an, t = terms(robot, q, task)
        poly = kinematic_polytope(t["J_u"], t["W"], t["velocity_limits"])
        ell = an.kinematic
        assert _facets_hold(poly, ell)  # ellipsoid inside polytope
        assert _vertices_in(ell, poly.vertices, math.sqrt(robot.nx))  # polytope inside sqrt(n) ellipsoid
        ratios.append(poly.radius_along(ell.axes[0]) / ell.semi_axes[0])
    assert min(ratios) >= 1.0 - 1e-12 and max(ratios) <= math.sqrt(robot.nx)


@pytest.mark.parametrize("name, task, count", [("paper", "planar", 100), ("tiago", "translational", 50)])
def test_dynamic_ellipsoid_inside_policy_polytope_inside_exact_polytope(request, rng, name, task, count):
    robot, _ = request.getfixturevalue(name)
    for _ in range(count):
        q = random_configuration(robot, rng) if name == "paper" else configuration_within_limits(robot, rng)
        an, t = terms(robot, q, task, 2.0)
        policy = min_norm_dynamic_polytope(**dynamic_terms(t))
        exact = dynamic_polytope(**dynamic_terms(t))
        if not an.dynamic.empty:
            assert _facets_hold(policy, an.dynamic)
        if not policy.empty:
            assert np.all(exact.contains(policy.vertices, tol=1e-9))


def test_spatial_sets_are_nested_along_random_directions(tiago, rng):
    robot, _ = tiago
    for _ in range(5):
        q = configuration_within_limits(robot, rng)
        an, t = terms(robot, q, "spatial", 2.0)
        d = _unit(rng, 30, 6)
        kin = kinematic_polytope(t["J_u"], t["W"], t["velocity_limits"]).supports(d)
        h_ell = np.array([an.kinematic.support(x) for x in d])
        assert np.all(h_ell <= kin * (1 + 1e-9)) and np.all(kin <= math.sqrt(robot.nx) * h_ell * (1 + 1e-9))
        policy = min_norm_dynamic_polytope(**dynamic_terms(t))
        if not policy.empty:
            assert np.all(policy.supports(d) <= dynamic_polytope(**dynamic_terms(t)).supports(d) + 1e-9)


# ---------------------------------------------------------------------------------------------
# Every vertex is reached, through Pinocchio


def _check_kinematic_vertices(robot, q, task, t):
    poly = kinematic_polytope(t["J_u"], t["W"], t["velocity_limits"])
    X = poly.vertex_inputs
    assert np.all(np.abs(X) <= t["velocity_limits"] * (1 + 1e-12))
    for v, x in zip(poly.vertices, X):
        np.testing.assert_allclose(hand_velocities(robot, q, x, task), t["W"].T @ v, rtol=0, atol=1e-9)
    return len(X)


def _check_dynamic_vertices(robot, q, task, t, poly):
    tau = poly.vertex_inputs
    assert np.all(np.abs(tau) <= t["effort_limits"] * (1 + 1e-12))
    for v, torque in zip(poly.vertices, tau):
        a = closed_chain_acceleration(robot, q, task, torque, t["W"], t["M_o"], t["g_o"])
        np.testing.assert_allclose(a, v, rtol=0, atol=1e-9)


@pytest.mark.parametrize("platform", ["mobile", "fixed"])
def test_paper_robot_vertices_are_reached_through_pinocchio(paper, platform):
    robot, q = paper
    if platform == "fixed":
        robot = robot.with_platform("fixed")
    _, t = terms(robot, q, "planar")
    assert _check_kinematic_vertices(robot, q, "planar", t) >= 4
    _check_dynamic_vertices(robot, q, "planar", t, dynamic_polytope(**dynamic_terms(t)))
    _check_dynamic_vertices(robot, q, "planar", t, min_norm_dynamic_polytope(**dynamic_terms(t)))


def test_tiago_translational_vertices_are_reached_through_pinocchio(tiago):
    robot, q = tiago
    _, t = terms(robot, q, "translational", 2.0)
    assert _check_kinematic_vertices(robot, q, "translational", t) > 50
    _check_dynamic_vertices(robot, q, "translational", t, dynamic_polytope(**dynamic_terms(t)))
    _check_dynamic_vertices(robot, q, "translational", t, min_norm_dynamic_polytope(**dynamic_terms(t)))


def test_policy_torques_are_the_papers_map(paper):
    """The inputs of the policy set are tau = Lambda_o a_o + mu_o (numpy's pinv, independently)."""
    robot, q = paper
    _, t = terms(robot, q, "planar")
    policy = min_norm_dynamic_polytope(**dynamic_terms(t))
    Lam, mu = policy_map(*list(dynamic_terms(t).values())[:-1])
    np.testing.assert_allclose(policy.vertex_inputs, policy.vertices @ Lam.T + mu, rtol=0, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# Overload and emptiness


def _flags(t, scale):
    """(ellipsoid empty, policy polytope empty) with every torque limit scaled by ``scale``."""
    d = dynamic_terms(t)
    d["effort_limits"] = t["effort_limits"] * scale
    return dynamic_ellipsoid(**d).empty, min_norm_dynamic_polytope(**d).empty


def _critical_scale(t, which: int) -> float:
    """The torque-limit scale below which the set is empty (bisection)."""
    lo, hi = 0.0, 1.0
    assert not _flags(t, hi)[which]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _flags(t, mid)[which] else (lo, mid)
    return hi


def test_policy_polytope_empties_after_the_ellipsoid(tiago):
    """||.||_inf <= ||.||_2: the ellipsoid is inside the polytope, so an empty polytope means an
    empty ellipsoid, not conversely. Weakening every motor, the ellipsoid empties first."""
    robot, q = tiago
    _, t = terms(robot, q, "translational", 2.0)
    ellipsoid_limit = _critical_scale(t, 0)
    polytope_limit = _critical_scale(t, 1)
    assert 0.0 < polytope_limit < ellipsoid_limit < 1.0
    for scale in np.linspace(0.5 * polytope_limit, 1.0, 25):
        ell_empty, poly_empty = _flags(t, scale)
        assert ell_empty or not poly_empty


def test_overload_gives_an_empty_policy_set_and_never_nan(tiago):
    """Motors too weak to hold arms and load (a tenth of their limits): the policy set is empty,
    flagged, with zero indices; the exact set is not (robot and object move somehow) but
    cannot hold the load still."""
    robot, q = tiago
    _, t = terms(robot, q, "translational", 2.0)
    d = dynamic_terms(t)
    d["effort_limits"] = t["effort_limits"] * 0.1
    policy = min_norm_dynamic_polytope(**d)
    assert policy.empty and policy.degenerate and dynamic_ellipsoid(**d).empty
    assert policy.support(np.ones(3)) == 0.0 and policy.volume == 0.0 and policy.isotropy == 0.0
    assert policy.radius_along(np.ones(3)) == 0.0 and policy.contains(np.zeros(3)) is False
    assert policy.vertices.shape == (0, 3)
    json.dumps(policy.to_dict(), allow_nan=False)
    exact = dynamic_polytope(**d)
    assert not exact.empty and not exact.contains(np.zeros(3))
    json.dumps(exact.to_dict(), allow_nan=False)
