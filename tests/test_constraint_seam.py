"""The constraint seam: a constraint from a new file (tests/toy_constraint.py) reaches analyze, the
JSON, sweeps of polytope indices and teams with no edit elsewhere, and every set under it is the
set computed a second way (the closed-form polytopes with the robot's limits scaled)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from conftest import paper_case
from mobmanip.errors import ArgumentError
from mobmanip.measures import get_measure
from mobmanip.sets.capacity import dynamic_polytope, kinematic_polytope, min_norm_dynamic_polytope
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
from mobmanip.team import analyze_team, load_team
from mobmanip.team.analysis import member_terms, stack_terms
from mobmanip.terms.builder import terms_at
from mobmanip.terms.constraints import ConstraintRows
from mobmanip.terms.problems import capacity_polytope
from toy_constraint import EffortShare, SpeedShare

ROOT = Path(__file__).resolve().parents[1]
DIRECTIONS = np.array([[np.cos(t), np.sin(t)] for t in np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)])


@pytest.fixture(scope="module")
def paper():
    return paper_case(30.0)


def _scaled(terms, share):
    return dataclasses.replace(terms, effort_limits=share * terms.effort_limits, constraints=())


def test_joint_boxes_alone_give_the_closed_forms(paper):
    """The linear programs with only the joint boxes equal the zonotope closed forms: the
    generic path is checked against the fast one before it carries other constraints."""
    robot, q = paper
    T = terms_at(robot, q, "planar", object_mass=2.0)
    pairs = [
        (capacity_polytope(T, "velocity"), kinematic_polytope(T.J_u, T.W, T.velocity_limits)),
        (
            capacity_polytope(T, "acceleration"),
            dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, T.effort_limits),
        ),
        (
            capacity_polytope(T, "acceleration", policy=True),
            min_norm_dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, T.effort_limits),
        ),
    ]
    for lifted, closed in pairs:
        scale = np.abs(closed.supports(DIRECTIONS)).max()
        np.testing.assert_allclose(lifted.supports(DIRECTIONS), closed.supports(DIRECTIONS), atol=1e-9 * scale)
        assert abs(lifted.volume - closed.volume) <= 1e-9 * closed.volume
        assert len(lifted.vertices) == len(closed.vertices)


def test_a_new_constraint_reaches_analyze_and_the_json(paper):
    robot, q = paper
    share = 0.4
    plain = mobmanip.analyze(robot, q, "planar", object_mass=2.0, measures=("dynamic", "dynamic_polytope"))
    result = mobmanip.analyze(
        robot, q, "planar", object_mass=2.0, measures=("dynamic", "dynamic_polytope", "dynamic_polytope_min_norm"),
        constraints=(EffortShare(share),),
    )  # fmt: skip
    T = _scaled(result.terms, share)
    exact = dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, T.effort_limits)
    policy = min_norm_dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, T.effort_limits)
    for name, closed in (("dynamic_polytope", exact), ("dynamic_polytope_min_norm", policy)):
        got = result.measures[name].supports(DIRECTIONS)
        np.testing.assert_allclose(got, closed.supports(DIRECTIONS), atol=1e-9 * np.abs(got).max())
    # the ellipsoid cannot honour it, says so, and is the unconstrained one
    assert result.ignored_constraints("dynamic") == ("effort_share",)
    assert result.ignored_constraints("dynamic_polytope") == ()
    np.testing.assert_allclose(result.dynamic.semi_axes, plain.dynamic.semi_axes, rtol=1e-12)
    doc = result.to_dict()
    assert doc["constraints"] == [{"name": "effort_share", "share": share, "problem": "acceleration"}]
    assert doc["dynamic_ellipsoid"]["ignored_constraints"] == ["effort_share"]
    assert doc["dynamic_polytope"]["ignored_constraints"] == []
    assert [c["name"] for c in doc["dynamic_polytope"]["model"]["constraints"]] == ["effort_limits", "effort_share"]
    # what binds at the straight-line maximum along +x: efforts at the toy's share of their limits
    witness = result.measures["dynamic_polytope"].straight_line_witness([1.0, 0.0])
    tau = witness.variables["tau"]
    assert np.max(np.abs(tau) / (share * robot.effort_limits)) == pytest.approx(1.0, abs=1e-9)
    assert witness.binding and all(f"at {share:g} of its effort limit" in label for label in witness.binding)
    # a velocity constraint leaves accelerations alone and the other way round
    k = mobmanip.analyze(robot, q, "planar", measures=("kinematic_polytope",), constraints=(SpeedShare(0.5),))
    K = k.terms
    closed = kinematic_polytope(K.J_u, K.W, 0.5 * K.velocity_limits)
    np.testing.assert_allclose(
        k.measures["kinematic_polytope"].supports(DIRECTIONS),
        closed.supports(DIRECTIONS),
        atol=1e-9 * closed.circumradius,
    )
    assert result.ignored_constraints("kinematic") == ()


def test_a_new_constraint_reaches_sweeps_of_polytope_indices():
    spec = SweepSpec(
        "planar_dual_arm", object_mass=2.0, measures=("dynamic", "dynamic_polytope"), constraints=(EffortShare(0.5),)
    )
    grid = SweepGrid(angle_deg=np.array([0.0, 60.0, 135.0]), distance=np.array([0.7, 0.9]))
    result = run_sweep(spec, grid, workers=1)
    assert result.ignored_constraints("dynamic") == ("effort_share",)
    assert result.ignored_constraints("dynamic_polytope") == ()
    robot = mobmanip.load_robot("planar_dual_arm")
    names, values = result.joint_positions()
    volume = result.index("dynamic_polytope.volume")
    checked = 0
    for i in range(len(grid.angle_deg)):
        for j in range(len(grid.distance)):
            if np.isnan(values[i, j]).any():
                continue
            q = robot.configuration((0.0, 0.0, 0.0), dict(zip(names, values[i, j])))
            T = _scaled(terms_at(robot, q, object_mass=2.0), 0.5)
            closed = dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, T.effort_limits)
            assert volume[i, j, 0] == pytest.approx(closed.volume, rel=1e-9)
            checked += 1
    assert checked >= 4


def test_a_new_constraint_reaches_teams():
    team = load_team(ROOT / "examples" / "two_arms_box.toml")
    share = 0.6
    constrained = analyze_team(
        team, measures=("dynamic_polytope", "kinematic_polytope"), constraints=(EffortShare(share),)
    )
    parts = member_terms(team)
    scaled = stack_terms(
        team, parts, {i: share for i in range(len(parts))}, quantity=get_measure("dynamic_polytope").quantity
    )
    closed = get_measure("dynamic_polytope").compute(scaled)
    m = constrained.terms.W.shape[0]
    directions = np.random.default_rng(3).normal(size=(16, m))
    got = constrained.measures["dynamic_polytope"].supports(directions)
    np.testing.assert_allclose(got, closed.supports(directions), atol=1e-8 * np.abs(got).max())
    # the velocity set has no constraint of its problem: the closed form, untouched
    plain = analyze_team(team, measures=("kinematic_polytope",))
    np.testing.assert_allclose(
        constrained.measures["kinematic_polytope"].supports(directions),
        plain.measures["kinematic_polytope"].supports(directions),
        rtol=1e-12,
    )


def test_bad_constraints_are_refused_with_their_name(paper):
    robot, q = paper
    with pytest.raises(ArgumentError, match="distinct names"):
        mobmanip.analyze(robot, q, measures=("dynamic_polytope",), constraints=(EffortShare(0.5), EffortShare(0.4)))
    with pytest.raises(ArgumentError, match="Constraint"):
        mobmanip.analyze(robot, q, measures=("dynamic_polytope",), constraints=("floor",))
    with pytest.raises(ArgumentError, match="'toy'.*expected 2 rows"):
        ConstraintRows("toy", "acceleration", G={"tau": np.zeros((3, 8))}, h=np.zeros(2))
    with pytest.raises(ArgumentError, match="unknown equations"):
        ConstraintRows("toy", "velocity", couplings={"dynamics": {}})


def test_a_users_rows_are_ranked_as_the_limits_they_stand_for(paper):
    """A constraint that gives no kinds or scales: its rows are of kind ``user``, each worth 1 % of
    its own bound. EffortShare(0.5) binds where the joint boxes of a robot with half the effort
    limits bind, and with the same gains, limit by limit, along each axis; bad kinds and scales are
    refused naming the constraint."""
    robot, q = paper
    shared = mobmanip.analyze(robot, q, measures=("dynamic_polytope",), constraints=(EffortShare(0.5),))
    halved = robot.with_limits(effort={name: 0.5 * v for name, v in robot.joint_effort_limits.items()})
    halved = halved.with_wheel_limits(effort=0.5 * float(robot.effort_limits[0]))
    # a share that never binds keeps the set one of linear programs, whose multipliers it reads
    reference = mobmanip.analyze(halved, q, measures=("dynamic_polytope",), constraints=(EffortShare(2.0),))
    for e in np.vstack([np.eye(2), -np.eye(2)]):
        mine = shared.measures["dynamic_polytope"].straight_line_witness(e).limits
        theirs = reference.measures["dynamic_polytope"].straight_line_witness(e).limits
        assert mine and {lim.kind for lim in mine} == {"user"} and {lim.kind for lim in theirs} == {"effort"}
        got = {lim.label.replace(" at 0.5 of its", ""): lim.gain for lim in mine}
        want = {lim.label: lim.gain for lim in theirs}
        assert set(got) == set(want)
        for label, gain in want.items():
            assert got[label] == pytest.approx(gain, rel=1e-6), label
    with pytest.raises(ArgumentError, match="'toy': unknown row kinds \\['slip'\\]"):
        ConstraintRows("toy", "acceleration", G={"tau": np.zeros((1, 8))}, h=np.ones(1), kinds=("slip",))
    with pytest.raises(ArgumentError, match="'toy': its row scales must be 1 positive"):
        ConstraintRows("toy", "acceleration", G={"tau": np.zeros((1, 8))}, h=np.ones(1), scales=(0.0,))


def test_the_policy_at_a_singular_posture_keeps_only_what_the_hands_can_follow():
    """Arms stretched (the paper robot's home): J_u loses rank; the lifted policy set blocks the
    directions the hands cannot follow, as the closed form does."""
    robot = mobmanip.load_robot("planar_dual_arm")
    T = terms_at(robot, robot.neutral(), "planar", object_mass=2.0)
    assert np.linalg.matrix_rank(T.J_u) < T.J_u.shape[0]
    lifted = capacity_polytope(T, "acceleration", policy=True)
    closed = min_norm_dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, T.effort_limits)
    scale = np.abs(closed.supports(DIRECTIONS)).max()
    np.testing.assert_allclose(lifted.supports(DIRECTIONS), closed.supports(DIRECTIONS), atol=1e-9 * scale)


def test_the_constraint_types_are_at_the_top_level_and_an_ignored_constraint_is_a_warning(capfd):
    """``mobmanip.Floor``, ``mobmanip.named_configuration`` and the constraint types are the ones
    their modules define. An analysis asked for a floor returns ellipsoids that cannot honour it:
    its warnings say so, per measure, and name the measures that do; an analysis of polytopes only
    has no such warning. The command line marks it in the summary and does not repeat it."""
    from hostile_util import run_cli
    from mobmanip.postures.named import named_configuration
    from mobmanip.terms.constraints import Constraint, ConstraintRows, EffortBox, VelocityBox
    from mobmanip.terms.constraints.floor import Floor

    assert (mobmanip.Floor, mobmanip.named_configuration) == (Floor, named_configuration)
    assert (mobmanip.Constraint, mobmanip.ConstraintRows) == (Constraint, ConstraintRows)
    assert (mobmanip.EffortBox, mobmanip.VelocityBox) == (EffortBox, VelocityBox)
    robot = mobmanip.load_robot("tiago_dual")
    q = mobmanip.named_configuration(robot, "hold")
    both = mobmanip.analyze(robot, q, measures=("dynamic", "dynamic_polytope"), constraints=(mobmanip.Floor(mu=0.5),))
    said = [w for w in both.warnings if "ignores" in w]
    assert said == [
        "the dynamic measure ignores the floor constraint(s) asked for: an ellipsoid cannot honour them; the "
        "polytopes do (dynamic_polytope, kinematic_polytope)"
    ]
    polytopes = mobmanip.analyze(robot, q, measures=("dynamic_polytope",), constraints=(mobmanip.Floor(mu=0.5),))
    assert not [w for w in polytopes.warnings if "ignores" in w]
    code, out, err = run_cli(capfd, "analyze", "tiago_dual", "--posture", "hold", "--ground")
    assert code == 0 and "[ignores floor" in out and "ignores the floor" not in err


def test_the_default_measures_with_a_floor_say_that_the_ellipsoids_ignore_it():
    """The call of issue 39 as a user writes it, with the default measures (the two ellipsoids):
    ``warnings`` is not empty but says that the dynamic ellipsoid ignores the floor. The velocity
    ellipsoid is not named: a floor limits forces, which no velocity depends on."""
    robot = mobmanip.load_robot("planar_dual_arm")
    found = mobmanip.analyze(robot, mobmanip.named_configuration(robot, "home"), constraints=(mobmanip.Floor(mu=0.5),))
    assert set(found.measures) == {"kinematic", "dynamic"}
    said = [w for w in found.warnings if "ignores" in w]
    assert len(said) == 1 and said[0].startswith("the dynamic measure ignores the floor constraint(s)")
    assert found.ignored_constraints("kinematic") == () and found.ignored_constraints("dynamic") == ("floor",)
