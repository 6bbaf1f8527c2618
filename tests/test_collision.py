"""Self-collision distances: gradients against central differences through pin.integrate, the
pair rules, properties, and placement keeping the margin."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import central_differences, random_configuration
from mobmanip.errors import ArgumentError
from mobmanip.placement import place
from mobmanip.robot.collision import SelfCollision

STEP = 1e-4


@pytest.fixture(scope="module")
def checker(paper):
    return SelfCollision(paper, margin=0.02)


def test_distance_gradients_equal_central_differences(paper, checker):
    """On 10 random configurations, every pair's distance gradient equals central differences of
    the distances through pin.integrate (to 1e-6 m per rad or m: GJK runs to 1e-10 m)."""
    model = paper.model
    rng = np.random.default_rng(4)
    for _ in range(10):
        q = random_configuration(paper, rng)
        d, G = checker.distances(q)
        fd = central_differences(lambda q: checker.distances(q)[0], model, q, STEP)
        smooth = np.abs(d - checker.activation) > 1e-3  # not at the clip
        np.testing.assert_allclose(G[smooth], fd[smooth], atol=1e-6)


def test_pair_rules(paper, checker):
    """No pair on one body or on adjacent links; every pair has a joint the placement moves
    between its bodies; no pair is closer than the margin in the reference hold."""
    model = paper.model
    moving = {model.getJointId(j) for arm in paper.arms for j in arm.joint_names}
    for pair in checker.pairs:
        a, b = pair.joints
        assert a != b and model.parents[a] != b and model.parents[b] != a
        assert (set(model.supports[a]) ^ set(model.supports[b])) & moving
    d, _ = checker.distances(paper.hold_configuration())
    assert d.min() >= checker.margin


def test_distances_do_not_depend_on_the_platform_pose(paper, checker):
    """Moving and turning the whole robot leaves every distance unchanged (to 1e-9 m)."""
    q = random_configuration(paper, np.random.default_rng(6))
    moved = q.copy()
    moved[:4] = (-2.0, 3.5, np.cos(2.2), np.sin(2.2))
    np.testing.assert_allclose(checker.distances(moved)[0], checker.distances(q)[0], atol=1e-9)


def test_paper_arms_pass_over_each_other_but_fold_onto_themselves(paper, checker):
    """The paper's two arms work in two horizontal planes: over 200 random configurations no pair
    across the arms comes closer than the margin (crossing arms in the top view do not collide),
    while an arm folded back (link 3 over link 1, one plane) does overlap."""
    rng = np.random.default_rng(7)
    across, within = np.inf, np.inf
    for _ in range(200):
        d, _ = checker.distances(random_configuration(paper, rng))
        for pair, value in zip(checker.pairs, d):
            if pair.first.startswith("arm_") and pair.second.startswith("arm_"):
                same = pair.first.split("_")[1] == pair.second.split("_")[1]
                if same:
                    within = min(within, value)
                else:
                    across = min(across, value)
    assert across > checker.margin
    assert within < 0.0


def test_placement_keeps_the_margin_where_it_binds(paper):
    """Minor semi-axis on the paper's robot: the unconstrained optimum brings link 3 within
    0.3 m of link 1; with a 0.3 m margin the result keeps it (checked by a fresh distance
    computation), still holds the object within the joint limits, and gives up some value."""
    from test_placement import check_holds

    target, objective = [1.0, 0.5, 0.35], "kinematic:minor_axis"
    checker = SelfCollision(paper, margin=0.3)
    free = place(paper, target, objective, starts=4)
    assert checker.clearance(free.q) < 0.3 - 1e-3
    kept = place(paper, target, objective, starts=4, collision=checker)
    assert SelfCollision(paper, margin=0.3).clearance(kept.q) >= 0.3 - 1e-6
    check_holds(paper, kept, orientation=False)
    assert kept.value <= free.value + 1e-9


def test_bad_collision_options(paper):
    with pytest.raises(ArgumentError, match="margin"):
        SelfCollision(paper, margin=-0.1)
    with pytest.raises(ArgumentError, match="source"):
        SelfCollision(paper, source="mesh")
