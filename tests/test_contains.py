"""``contains`` answers as NumPy does (issue 39): one point, shape (m,), is a Python ``bool``; points
(n, m) are a bool array (n,), also for n = 1 and n = 0; any other shape is one error naming it.

For every kind of set (ellipsoid, zonotope, zonotope section, the floor's lifted polytope, empty
sets) the answers are checked against what is known without the set's own query: its centre is
inside (or nothing is, when it is empty) and a point twice its support along a direction is not.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from mobmanip.errors import SetQueryError
from mobmanip.sets.ellipsoid import Ellipsoid
from mobmanip.sets.polytope import Polytope


def _sets(paper):
    rng = np.random.default_rng(7)
    q = mobmanip.named_configuration(paper, "home")
    grounded = mobmanip.analyze(paper, q, measures=("dynamic_polytope",), constraints=(mobmanip.Floor(mu=0.5),))
    return {
        "ellipsoid": Ellipsoid.from_generator(rng.normal(size=3), rng.normal(size=(3, 5))),
        "zonotope": Polytope.zonotope(rng.normal(size=3), rng.normal(size=(3, 6))),
        "section": Polytope(rng.normal(size=(5, 3)), np.zeros(5), rng.normal(size=(5, 8))),
        "lifted": grounded.measure("dynamic_polytope"),
    }


@pytest.fixture(scope="module")
def sets(paper):
    return _sets(paper)


@pytest.mark.parametrize("kind", ["ellipsoid", "zonotope", "section", "lifted"])
def test_one_point_is_a_bool_and_points_are_an_array(sets, kind):
    task_set = sets[kind]
    m = task_set.dim
    d = np.eye(m)[0]
    outside = task_set.center + 2.0 * (task_set.support(d) - d @ task_set.center + 1.0) * d
    for point, expected in ((task_set.center, True), (outside, False)):
        answer = task_set.contains(point)
        assert type(answer) is bool and answer is expected
        assert task_set.contains(tuple(point.tolist())) is expected  # any sequence of m numbers
    both = task_set.contains(np.stack([task_set.center, outside]))
    assert isinstance(both, np.ndarray) and both.dtype == bool and both.tolist() == [True, False]
    one = task_set.contains(task_set.center[None])  # a batch of one stays a batch
    assert isinstance(one, np.ndarray) and one.shape == (1,) and one.tolist() == [True]
    none = task_set.contains(np.zeros((0, m)))
    assert isinstance(none, np.ndarray) and none.shape == (0,)


@pytest.mark.parametrize("kind", ["ellipsoid", "zonotope", "section", "lifted"])
def test_a_bad_shape_is_one_error_naming_it(sets, kind):
    task_set = sets[kind]
    m = task_set.dim
    for bad in (np.zeros(m + 1), np.zeros((2, m + 1)), np.zeros((2, m, 1)), np.zeros((m, 1)).T[None], 0.0):
        with pytest.raises(SetQueryError) as info:
            task_set.contains(bad)
        message = str(info.value)
        assert str(np.shape(bad)) in message and f"({m},)" in message and f"(n, {m})" in message
    with pytest.raises(SetQueryError, match="finite"):
        task_set.contains(np.r_[np.nan, np.zeros(m - 1)])


def test_empty_sets_answer_false_in_the_same_shapes():
    """An empty ellipsoid and two boxes that do not meet (a in [-1, 1] and a in [2, 4])."""
    empty_ellipsoid = Ellipsoid.from_generator(np.zeros(2), np.eye(2), empty=True)
    apart = Polytope([[1.0], [1.0]], [0.0, 3.0], np.eye(2))
    assert apart.empty and empty_ellipsoid.empty
    assert empty_ellipsoid.contains(np.zeros(2)) is False
    assert empty_ellipsoid.contains(np.zeros((3, 2))).tolist() == [False] * 3
    assert apart.contains([0.0]) is False and apart.contains(0.0) is False  # a scalar is one point when m = 1
    assert apart.contains([[0.0], [2.5]]).tolist() == [False, False]


def test_a_one_dimensional_set_takes_a_scalar_as_one_point():
    segment = Polytope.zonotope([1.0], [[2.0]])  # [-1, 3]
    assert segment.contains(0.0) is True and segment.contains(3.5) is False
    assert segment.contains([[0.0], [3.5]]).tolist() == [True, False]
    assert segment.contains([0.0]) is True  # shape (1,) is one point of a 1-D set
