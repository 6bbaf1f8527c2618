"""The certified fast path of the polytope projections (mobmanip.sets.linear_programs.CertifiedProgram):
DAQP's answers are kept only with an optimality certificate, else HiGHS answers. Checked against
HiGHS itself on random programs, and on the grounded polygons against their own HiGHS supports."""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.sets.linear_programs import CertifiedProgram, LinearProgram
from mobmanip.terms.constraints.floor import Floor


def _random_program(rng, n=12, p=4, r=20):
    """A bounded, feasible program: equalities and inequalities through a known interior point."""
    x0 = rng.uniform(-1.0, 1.0, n)
    E, G = rng.normal(size=(p, n)), rng.normal(size=(r, n))
    A = np.vstack([E, G])
    lo = np.r_[E @ x0, np.full(r, -np.inf)]
    hi = np.r_[E @ x0, G @ x0 + rng.uniform(0.1, 2.0, r)]
    return A, lo, hi, np.full(n, -3.0), np.full(n, 3.0)


def test_certified_answers_equal_highs_on_random_programs():
    rng = np.random.default_rng(7)
    certified = 0
    for _ in range(20):
        A, lo, hi, cl, ch = _random_program(rng)
        highs = LinearProgram(A, lo, hi, cl, ch)
        fast = CertifiedProgram(A, lo, hi, cl, ch, lambda p=(A, lo, hi, cl, ch): LinearProgram(*p))
        for _ in range(10):
            c = rng.normal(size=A.shape[1])
            value, x = fast.solve(c)
            reference = highs.solve(c)
            assert reference is not None
            assert value == pytest.approx(reference[0], rel=1e-9, abs=1e-9)
            assert value == pytest.approx(c @ x, rel=1e-12, abs=1e-12)
            assert np.all(A @ x <= hi + 1e-8) and np.all(A @ x >= lo - 1e-8)
            assert np.all(x <= ch + 1e-8) and np.all(x >= cl - 1e-8)
        certified += fast.certified
    assert certified >= 150  # the fast path answers most of the 200 programs itself


def test_an_infeasible_program_is_none_and_a_wrong_answer_fails_its_certificate():
    A = np.array([[1.0, 1.0], [1.0, -1.0]])
    lo, hi = np.array([3.0, -np.inf]), np.array([3.0, 0.0])
    cl, ch = np.array([-1.0, -1.0]), np.array([1.0, 1.0])  # x + y = 3 is out of the box
    fast = CertifiedProgram(A, lo, hi, cl, ch, lambda: LinearProgram(A, lo, hi, cl, ch))
    assert fast.solve(np.array([1.0, 0.0])) is None and fast.fell_back == 1
    lo, hi = np.array([1.0, -np.inf]), np.array([1.0, 0.0])
    ok = CertifiedProgram(A, lo, hi, cl, ch, lambda: LinearProgram(A, lo, hi, cl, ch))
    value, x = ok.solve(np.array([1.0, 0.0]))  # max x s.t. x + y = 1, x <= y: x = 1/2
    assert value == pytest.approx(0.5, abs=1e-9) and ok.certified + ok.fell_back == 1  # to the certificate's 1e-9
    f = -np.array([1.0, 0.0])
    lam = np.zeros(4)
    lam[2], lam[3] = 0.5, 0.5  # f + A' lam = 0 with x + y = 1 and x - y <= 0 active
    assert ok._certify(f, x, lam)
    assert not ok._certify(f, x + [0.01, -0.01], lam)  # infeasible: x - y > 0
    assert ok._certify(f, x, lam * 1.01)  # multipliers off: recomputed on the same active rows
    assert not ok._certify(f, x, np.array([0.0, 0.0, 0.5, 0.0]))  # no multipliers balance f on x + y = 1
    assert not ok._certify(f, x - [0.1, -0.1], lam)  # x - y < 0 where its multiplier says active


@pytest.mark.parametrize("angle", [0.0, 90.0])
@pytest.mark.parametrize("floor", [Floor(mu=0.5), Floor(mu=None), Floor(mu=1.0, reserve=0.1)], ids=str)
def test_grounded_polygons_have_highs_supports_and_no_straight_vertices(angle, floor):
    robot = mobmanip.load_robot("planar_dual_arm")
    q = configuration_at(robot, optimal_posture(robot), angle)
    P = mobmanip.analyze(
        robot, q, "planar", object_mass=2.0, measures=("dynamic_polytope",), constraints=(floor,)
    ).measures["dynamic_polytope"]
    V = P.vertices
    for t in np.linspace(0.0, 2.0 * np.pi, 97)[:-1]:
        d = np.array([np.cos(t), np.sin(t)])
        assert (V @ d).max() == pytest.approx(P.support(d), rel=1e-9)  # support: HiGHS with duals
    u, w = V - np.roll(V, 1, axis=0), np.roll(V, -1, axis=0) - V  # the edges into and out of each vertex
    turns = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
    scale = np.abs(V).max() ** 2
    assert turns.min() > 1e-9 * scale  # counter-clockwise, every vertex a corner


def test_changed_row_bounds_equal_a_program_built_with_them():
    """LinearProgram.solve(..., row_lo, row_hi): rows switched off (+-inf) or moved in place give
    the optimum of a program built afresh with those bounds, and the bounds stay for the next call
    (the held reach's program switches the samples after a run off this way)."""
    rng = np.random.default_rng(11)
    for _ in range(10):
        A, lo, hi, cl, ch = _random_program(rng)
        program = LinearProgram(A, lo, hi, cl, ch)
        built_lo, built_hi = program.row_bounds()
        assert np.array_equal(built_lo, lo) and np.array_equal(built_hi, hi)
        built_lo[0] = 5.0  # a copy: the program's own bounds do not move
        assert program.row_bounds()[0][0] == lo[0]
        c = rng.normal(size=A.shape[1])
        new_lo, new_hi = lo.copy(), hi.copy()
        new_lo[-8:], new_hi[-8:] = -np.inf, np.inf  # eight inequalities switched off
        new_hi[4:8] += 0.5  # four moved
        changed = program.solve(c, True, cl, ch, new_lo, new_hi)
        fresh = LinearProgram(A, new_lo, new_hi, cl, ch).solve(c)
        assert changed is not None and fresh is not None
        assert changed[0] == pytest.approx(fresh[0], rel=1e-9, abs=1e-9)
        again = program.solve(c)  # the changed bounds stay
        assert again is not None and again[0] == pytest.approx(fresh[0], rel=1e-9, abs=1e-9)
        restored = program.solve(c, True, cl, ch, lo, hi)
        original = LinearProgram(A, lo, hi, cl, ch).solve(c)
        assert restored is not None and original is not None
        assert restored[0] == pytest.approx(original[0], rel=1e-9, abs=1e-9)
        assert fresh[0] >= original[0] - 1e-9  # fewer and looser rows: no lower optimum


def test_the_floor_programs_are_answered_by_the_certified_path():
    """A grounded set's programs (forces of hundreds of newtons beside accelerations of a few
    m/s^2, many rows tight at once) are where DAQP's proximal iterations used to stop short:
    answers flagged optimal yet below the optimum (at TIAGo++'s home, 5 of the 12 axis
    directions), which the certificate refused and HiGHS solved again. Along the axes and the
    translational block's directions, the ones a set's projections ask for, every support now
    comes certified from DAQP itself and equals HiGHS's optimum of the program built from the
    set's public rows, and the set's own support."""
    robot = mobmanip.load_robot("tiago_dual")
    P = mobmanip.analyze(
        robot, robot.neutral(), "spatial", measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    ).measures["dynamic_polytope"]
    rows = P.lifted_rows()
    A = np.vstack([rows.A_eq, rows.A_ub])
    lo = np.r_[rows.b_eq, np.full(len(rows.b_ub), -np.inf)]
    hi = np.r_[rows.b_eq, rows.b_ub]
    highs = LinearProgram(A, lo, hi, rows.lower, rows.upper)
    fast = CertifiedProgram(A, lo, hi, rows.lower, rows.upper, lambda: LinearProgram(A, lo, hi, rows.lower, rows.upper))
    directions = list(np.vstack([np.eye(6), -np.eye(6)]))
    rng = np.random.default_rng(5)
    for _ in range(36):
        d = np.zeros(6)
        d[:3] = rng.normal(size=3)
        directions.append(d / np.linalg.norm(d))
    for d in directions:
        cost = np.zeros(A.shape[1])
        cost[rows.task] = d
        value, x = fast.solve(cost)
        reference = highs.solve(cost)
        assert reference is not None
        assert value == pytest.approx(reference[0], rel=1e-9, abs=1e-9)
        assert value == pytest.approx(P.support(d), rel=1e-9, abs=1e-9)
        assert np.all(A @ x <= hi + 1e-8 * (1 + np.abs(hi))) and np.all(A @ x >= lo - 1e-8 * (1 + np.abs(lo)))
    assert (fast.certified, fast.fell_back) == (48, 0)
