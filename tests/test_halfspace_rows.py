"""Halfspaces without repeated rows (issue 39): a facet that several generator subsets give (coplanar
generators, zonotope facets a section pulls back onto one task halfspace, Qhull's simplices of one
facet) is one row of ``halfspaces``, and the rows describe the same set as before.

The rule (:func:`mobmanip.sets.polytope_vertices.distinct_rows`): each row divided by the length of
its normal; two rows are one when their normals agree to 1e-9 in every coordinate and their offsets
to 1e-9 of the set's size. The references: a prism whose facets are counted by hand, the support
function of a zonotope in closed form (``d . c + sum_j |d . g_j|``), scipy's ``linprog`` written
from the definition {a : F a = c + G y, |y| <= 1}, and a pairwise comparison written here.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import mobmanip
from mobmanip.sets.polytope import Polytope
from mobmanip.sets.polytope_vertices import DUPLICATE_RTOL, distinct_rows

#: (robot, measure, task coordinates kept): zonotopes with coplanar or parallel generators (the
#: UR5's and TIAGo's translational shadows held repeated rows), in 3 and in 6 dimensions.
ROBOT_SETS = [
    ("ur5", "dynamic_polytope", (0, 1, 2)),
    ("tiago", "kinematic_polytope", (0, 1, 2)),
    ("tiago", "kinematic_polytope", (0, 1, 2, 3, 4, 5)),
    ("panda", "dynamic_polytope", (0, 1, 2, 3, 4, 5)),
]


def _repeated_pairs(A: np.ndarray, b: np.ndarray, size: float) -> list[tuple[int, int]]:
    """Pairs of rows that are one halfspace under the stated rule, by brute force."""
    length = np.linalg.norm(A, axis=1)
    An, bn = A / length[:, None], b / length
    out = []
    for i in range(len(A)):
        for j in range(i + 1, len(A)):
            if np.abs(An[i] - An[j]).max() <= DUPLICATE_RTOL and abs(bn[i] - bn[j]) <= DUPLICATE_RTOL * size:
                out.append((i, j))
    return out


def _halfspace_support(A: np.ndarray, b: np.ndarray, d: np.ndarray) -> float:
    res = linprog(-d, A_ub=A, b_ub=b, bounds=[(None, None)] * len(d), method="highs")
    assert res.status == 0
    return -res.fun


def _section_support(F, c, G, d) -> float:
    m, n = F.shape[1], G.shape[1]
    res = linprog(
        np.r_[-d, np.zeros(n)], A_eq=np.hstack([F, -G]), b_eq=c, bounds=[(None, None)] * m + [(-1, 1)] * n,
        method="highs",
    )  # fmt: skip
    assert res.status == 0
    return -res.fun


def test_the_rule_merges_scaled_copies_and_keeps_opposite_and_parallel_rows():
    """A copy scaled by 2 and a copy within 1e-12 are one row; the opposite row (an equality's other
    side) and a parallel row further out are other halfspaces; the first of each group is kept."""
    A = np.array([[1.0, 0.0], [2.0, 0.0], [-1.0, 0.0], [1.0, 0.0], [0.0, 3.0], [0.0, 1.0 + 1e-12], [1.0, 0.0]])
    b = np.array([1.0, 2.0, 1.0, 1.5, 3.0, 1.0, 1.0 + 1e-12])
    keep, inverse = distinct_rows(A, b, 1.0)
    assert keep.tolist() == [0, 2, 3, 4]
    assert inverse.tolist() == [0, 0, 1, 2, 3, 3, 0]


def test_many_rows_group_as_the_pairwise_rule_says():
    """300 rows in 3 dimensions with copies planted among them: scaled by a positive factor, moved
    by 1e-12, and a chain of three unit normals turned by 0.8e-9 rad each (the ends 1.3e-9 apart
    in a coordinate, past the tolerance; each within 0.7e-9 of the middle: one halfspace by
    transitivity). The groups equal those a union of the brute-force pairs gives, the first row of
    each group kept."""
    rng = np.random.default_rng(4)
    A = rng.normal(size=(300, 3))
    b = rng.uniform(0.5, 2.0, 300)
    A[10], b[10] = 3.0 * A[200], 3.0 * b[200]  # a scaled copy listed before its original
    A[50], b[50] = A[7] + 1e-12, b[7]
    A[120] = np.array([0.6, 0.8, 0.0])  # a chain of unit normals along a circle, the offsets equal
    A[121] = np.array([np.cos(0.9272952180016122 - 0.8e-9), np.sin(0.9272952180016122 - 0.8e-9), 0.0])
    A[122] = np.array([np.cos(0.9272952180016122 - 1.6e-9), np.sin(0.9272952180016122 - 1.6e-9), 0.0])
    b[120] = b[121] = b[122] = 1.0
    pairs = _repeated_pairs(A, b, 1.0)
    assert (120, 121) in pairs and (121, 122) in pairs and (120, 122) not in pairs
    keep, inverse = distinct_rows(A, b, 1.0)
    leader = list(range(len(A)))

    def root(i):
        while leader[i] != i:
            i = leader[i]
        return i

    for i, j in pairs:
        a, c = root(i), root(j)
        leader[max(a, c)] = min(a, c)
    roots = [root(i) for i in range(len(A))]
    assert keep.tolist() == sorted(set(roots))
    assert [keep[k] for k in inverse] == roots
    assert roots[200] == 10 and roots[50] == 7 and roots[121] == roots[122] == 120
    assert len(keep) == 300 - 4


def test_a_prism_of_coplanar_generators_has_one_row_per_facet():
    """G = [e1, e2, e1 + e2, e3]: a hexagon (the three coplanar generators) times a segment, 8
    facets; the top and bottom normal comes from three generator pairs each. Asked first for its
    halfspaces or first for its vertices, it lists 8 rows, the same ones."""
    G = np.array([[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    c = np.array([0.5, -0.2, 0.1])
    first = Polytope.zonotope(c, G)
    A, b = first.halfspaces
    second = Polytope.zonotope(c, G)
    assert len(second.vertices) == 12
    A2, b2 = second.halfspaces
    assert len(A) == len(A2) == 8
    as_set = lambda A, b: sorted(np.round(np.c_[A, b], 9).tolist())  # noqa: E731
    assert as_set(A, b) == as_set(A2, b2)
    top = np.flatnonzero(np.isclose(A[:, 2], 1.0))
    assert len(top) == 1 and b[top[0]] == pytest.approx(c[2] + 1.0)


def test_a_section_that_pulls_two_zonotope_facets_onto_one_halfspace_lists_it_once(rng):
    """F repeats a task row: zonotope facets with normals (n, 0, 0) and (0, 0, n) pull back to one
    task halfspace. One row remains, and the rows bound the set the definition gives."""
    F = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    G = np.array([[1.0, 0.0, 0.0, 0.5], [0.0, 1.0, 0.0, 0.5], [0.0, 0.0, 1.0, 0.5]])
    c = np.zeros(3)
    poly = Polytope(F, c, G)
    A, b = poly.halfspaces
    assert _repeated_pairs(A, b, 1.0) == []
    for d in rng.normal(size=(30, 2)):
        assert _halfspace_support(A, b, d) == pytest.approx(_section_support(F, c, G, d), rel=1e-9, abs=1e-9)


@pytest.fixture(scope="module")
def robot_sets():
    out = {}
    for name, measure, dims in ROBOT_SETS:
        robot = mobmanip.load_robot(name)
        analysis = mobmanip.analyze(robot, mobmanip.named_configuration(robot, "home"), measures=(measure,))
        out[name, measure, dims] = analysis.measure(measure).project(dims)
    return out


@pytest.mark.parametrize("key", ROBOT_SETS, ids=lambda k: f"{k[0]}-{k[1]}-{len(k[2])}d")
def test_robot_sets_list_each_halfspace_once_and_bound_the_same_set(robot_sets, key, rng):
    """On four robots' sets no two rows are one halfspace, and the rows bound exactly the zonotope:
    the largest d . a over them is the closed-form support, along random directions, and every
    vertex (3-D) lies on at least three of them."""
    poly = robot_sets[key]
    assert poly.is_zonotope and not poly.empty
    A, b = poly.halfspaces
    scale = float(np.linalg.norm(poly.generators, 2))  # at most the set's size the rule scales by
    assert _repeated_pairs(A, b, scale) == []
    for d in rng.normal(size=(12, poly.dim)):
        exact = d @ poly.center + np.abs(d @ poly.generators).sum()
        assert _halfspace_support(A, b, d) == pytest.approx(exact, rel=1e-8, abs=1e-9 * scale)
    if poly.dim == 3:
        slack = b[None, :] - poly.vertices @ A.T
        assert slack.min() >= -1e-9 * scale
        assert np.all((np.abs(slack) <= 1e-7 * scale).sum(axis=1) >= 3)


def test_a_grounded_set_lists_each_halfspace_once(paper):
    """The lifted (floor) polygon of the paper robot: its rows are distinct and bound its vertices."""
    q = mobmanip.named_configuration(paper, "home")
    found = mobmanip.analyze(paper, q, measures=("dynamic_polytope",), constraints=(mobmanip.Floor(mu=0.5),))
    poly = found.measure("dynamic_polytope")
    A, b = poly.halfspaces
    size = float(np.ptp(poly.vertices, axis=0).max())
    assert _repeated_pairs(A, b, size) == []
    slack = b[None, :] - poly.vertices @ A.T
    assert slack.min() >= -1e-9 * size and np.all((np.abs(slack) <= 1e-7 * size).sum(axis=1) >= 2)
