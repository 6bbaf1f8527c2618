"""The independent floor reference (tests/floor_reference.py) checked against mathematics.

It must be the same robot as mobmanip's (its ideal mode reproduces mobmanip's exact dynamic
polytope), obey statics (at rest the floor carries the weight under the centre of mass), match
the numbers issue 24 measured with an LP of this kind, and tip exactly where tipping begins.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import floor_reference as fr
import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.postures.named import named_configuration

MASS = 2.0  # kg, the object of issue 24's table
EX = np.array([1.0, 0.0])
EY = np.array([0.0, 1.0])


class Case:
    """One robot, configuration and task with its mobmanip analysis and the floor problem."""

    def __init__(self, robot, q, task, casters=None):
        self.robot, self.q, self.task = robot, q, task
        self.analysis = mobmanip.analyze(
            robot, q, task=task, object_mass=MASS, measures=("dynamic_polytope", "dynamic_polytope_min_norm")
        )
        self.problem = fr.build_problem(robot, q, task, self.analysis.held_object, casters=casters, level=True)

    def axis(self, k, sign=1.0):
        e = np.zeros(self.problem.W.shape[0])
        e[k] = sign
        return e


@pytest.fixture(scope="module")
def tiago():
    robot = mobmanip.load_robot("tiago_dual")
    return Case(robot, named_configuration(robot, "hold"), "spatial")


@pytest.fixture(scope="module")
def paper_robot():
    robot = mobmanip.load_robot("planar_dual_arm")
    return robot, optimal_posture(robot)


@pytest.fixture(scope="module")
def paper0(paper_robot):
    robot, posture = paper_robot
    return Case(robot, configuration_at(robot, posture, angle_deg=0.0), "planar", casters=fr.PAPER_CASTERS)


@pytest.fixture(scope="module")
def paper90(paper_robot):
    robot, posture = paper_robot
    return Case(robot, configuration_at(robot, posture, angle_deg=90.0), "planar", casters=fr.PAPER_CASTERS)


@pytest.fixture(params=["tiago", "paper0", "paper90"])
def case(request):
    return request.getfixturevalue(request.param)


def _directions(m, count=4, seed=7):
    rng = np.random.default_rng(seed)
    random = rng.normal(size=(count, m))
    return list(np.vstack([np.eye(m), -np.eye(m), random / np.linalg.norm(random, axis=1, keepdims=True)]))


# ----- the same robot as mobmanip's -----


def test_free_flyer_model_is_mobmanips_robot(case):
    robot, P = case.robot, case.problem
    model = fr.free_flyer_model(robot)
    assert list(model.names[2:]) == list(robot.model.names[2:])
    assert pin.computeTotalMass(model) == pytest.approx(pin.computeTotalMass(robot.model), rel=1e-12)
    # Q = I: entry k of tau is the torque of joint reduced_velocity_names[k] (up to a wheel's sign), and
    # its limit is that joint's URDF limit (the specs used here override none).
    np.testing.assert_allclose(P.S.T @ P.B, np.eye(robot.nx), atol=1e-15)
    for k, name in enumerate(robot.reduced_velocity_names):
        v = model.joints[model.getJointId(name)].idx_v
        assert np.flatnonzero(P.B[:, k]).tolist() == [v]
        assert robot.effort_limits[k] == pytest.approx(model.effortLimit[v])
    # The grasp matrix built from the hands and the centre, and the hands' Jacobians through S_f.
    np.testing.assert_allclose(P.W, case.analysis.grasp_matrix, atol=1e-12)
    np.testing.assert_allclose(P.hand_jacobian @ P.S, case.analysis.unified_jacobian, atol=1e-12)
    # A planar task's level rows (the object's weight, its roll and pitch) load the paper robot's
    # structure only: no work on x, which is why the ideal mode still is mobmanip's reduced model.
    assert np.abs(P.S.T @ P.level_jacobian.T).max(initial=0.0) <= 1e-12


def test_contacts_roll_and_casters_stay_on_the_floor(case):
    """J_c S_f = 0 at a driven wheel's contact (rolling without slip, every direction); a caster's
    contact has no vertical velocity but does slide (its swivel is not modelled: frictionless)."""
    P = case.problem
    for contact, J in zip(P.contacts, P.contact_jacobians):
        JS = J @ P.S
        if contact.driven:
            assert np.abs(JS).max() <= 1e-12, contact.name
        else:
            assert np.abs(JS[2]).max() <= 1e-12, contact.name
            assert np.abs(JS[:2]).max() > 1e-2, contact.name
    assert np.ptp(P.points[:, 2]) <= 1e-12  # every contact on one floor plane


def test_tiago_support_points_from_the_urdf(tiago):
    """Wheels below their centres by 0.0985 m, casters below theirs by their 0.025 m spheres."""
    names = [c.name for c in tiago.problem.contacts]
    assert names[:2] == ["wheel_right_joint", "wheel_left_joint"]
    assert sorted(names[2:]) == sorted(
        f"caster_{fb}_{lr}_2_link" for fb in ("front", "back") for lr in ("left", "right")
    )
    xy = {name: tiago.problem.points[i, :2] for i, name in enumerate(names)}
    np.testing.assert_allclose(xy["wheel_right_joint"], (0.0, -0.2022), atol=1e-12)
    np.testing.assert_allclose(xy["caster_front_left_2_link"], (0.1695 - 0.016, 0.102), atol=1e-12)
    np.testing.assert_allclose(xy["caster_back_right_2_link"], (-0.1735 - 0.016, -0.102), atol=1e-12)
    np.testing.assert_allclose(tiago.problem.points[:, 2], 0.0, atol=1e-12)  # base_footprint on the floor


# ----- 1. ideal mode is mobmanip's exact dynamic polytope -----


def test_ideal_mode_equals_mobmanips_exact_dynamic_polytope(case):
    exact = case.analysis.measures["dynamic_polytope"]
    policy = case.analysis.measures["dynamic_polytope_min_norm"]
    for e in _directions(case.problem.W.shape[0]):
        assert fr.support(case.problem, e).value == pytest.approx(exact.support(e), rel=1e-6)
        assert fr.support(case.problem, e, policy=True).value == pytest.approx(policy.support(e), rel=1e-6)


# ----- 2. statics -----


def test_at_rest_the_floor_carries_the_weight_under_the_centre_of_mass(case):
    """xdot = 0, a_o = 0: the contact forces sum to (robot + object) g, straight up, and their ZMP is
    the horizontal projection of the centre of mass of robot and object (the object's weight acts
    at its centre), inside the support polygon."""
    robot, P = case.robot, case.problem
    robot_mass = pin.computeTotalMass(robot.model)
    com = pin.centerOfMass(robot.model, robot.model.createData(), case.q)
    center = case.analysis.held_object.center
    com_xy = (robot_mass * com[:2] + MASS * center[:2]) / (robot_mass + MASS)
    for mode, mu in (("no_tip", None), ("friction", 0.5)):
        rest = fr.equilibrium(P, mode=mode, mu=mu)
        total = rest.forces.sum(axis=0)
        assert total[2] == pytest.approx((robot_mass + MASS) * fr.GRAVITY, rel=1e-9)
        np.testing.assert_allclose(total[:2], 0.0, atol=1e-7)
        assert rest.forces[:, 2].min() >= -1e-9
        np.testing.assert_allclose(rest.zmp[:2], com_xy, atol=1e-9)
        assert fr.polygon_margin(fr.support_polygon(P.points), rest.zmp) > 0.0


def test_a_maximiser_satisfies_every_equation_and_limit(case):
    P, mu, e = case.problem, 0.5, case.axis(0, -1.0)
    sol = fr.straight_line(P, e, mode="friction", mu=mu)
    generalized = sum(J.T @ f for J, f in zip(P.contact_jacobians, sol.forces))
    hands = P.hand_jacobian.T @ sol.h + P.level_jacobian.T @ sol.h_level
    residual = P.M @ P.S @ sol.xdot + P.g - P.B @ sol.tau - generalized + hands
    assert np.abs(residual).max() <= 1e-6 * np.abs(P.g).max()
    np.testing.assert_allclose(P.hand_jacobian @ P.S @ sol.xdot, P.W.T @ sol.a_o, atol=1e-6)
    np.testing.assert_allclose(P.W @ sol.h, P.M_o @ sol.a_o + P.g_o, atol=1e-6)
    np.testing.assert_allclose(sol.a_o, sol.value * e, atol=1e-9)
    np.testing.assert_allclose(P.level_grasp[0] @ sol.h + P.level_grasp[1] @ sol.h_level, P.level_load, atol=1e-6)
    assert np.all(np.abs(sol.tau) <= P.tau_max + 1e-9)
    for contact, f in zip(P.contacts, sol.forces):
        assert f[2] >= -1e-9
        limit = mu * f[2] if contact.driven else 0.0  # a caster has no tangential force at all
        assert math.hypot(f[0], f[1]) <= limit + 1e-9, contact.name


def test_each_floor_model_is_inside_the_one_before(tiago, paper0):
    """The constraint sets nest, so do the reaches: ideal >= no tip >= mu = 1 >= mu = 0.5."""
    for P, e, policy in ((tiago.problem, tiago.axis(0), False), (paper0.problem, EY, True)):
        values = [
            fr.straight_line(P, e, mode=mode, mu=mu, policy=policy).value
            for mode, mu in (("ideal", None), ("no_tip", None), ("friction", 1.0), ("friction", 0.5))
        ]
        assert all(a >= b - 1e-9 for a, b in zip(values, values[1:])), values


# ----- 3. issue 24's table -----

# (robot, axis sign, model, mu, issue's value): straight-line reach (m/s^2), 2 decimals as printed.
TIAGO_TABLE = [
    (+1, "ideal", None, 48.65),
    (+1, "no_tip", None, 38.89),
    (+1, "friction", 0.5, 37.08),
    (-1, "ideal", None, 47.51),
    (-1, "no_tip", None, 32.25),
    (-1, "friction", 0.5, 27.87),
]


@pytest.mark.parametrize(("sign", "mode", "mu", "expected"), TIAGO_TABLE)
def test_issue_table_tiago_hold_straight_line_x(tiago, sign, mode, mu, expected):
    assert round(fr.straight_line(tiago.problem, tiago.axis(0, sign), mode=mode, mu=mu).value, 2) == expected


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_issue_table_paper_robot_minimum_norm_y(paper0, sign):
    """30.25 ideal and without tip-over; "about 4.3" with mu = 0.5 (here 4.29 along +y, 4.37 along -y).

    The planar task has no vertical row, but the hands still carry the object's 2 kg down into the
    robot and the floor: without that load the reference gives 4.65 and 4.74 (it moves weight from
    the wheels to the front casters).
    """
    P, e = paper0.problem, sign * EY
    assert round(fr.straight_line(P, e, policy=True).value, 2) == 30.25
    assert round(fr.straight_line(P, e, mode="no_tip", policy=True).value, 2) == 30.25
    assert fr.straight_line(P, e, mode="friction", mu=0.5, policy=True).value == pytest.approx(4.3, abs=0.1)
    if sign > 0:
        assert round(fr.straight_line(P, e, mode="friction", mu=0.5, policy=True).value, 1) == 4.3


def test_issue_support_and_straight_line_differ_on_tiago(tiago):
    """Issue 24: along +y TIAGo++'s support is 46.99 m/s^2, its straight-line reach 27.42."""
    assert round(fr.support(tiago.problem, tiago.axis(1)).value, 2) == 46.99
    assert round(fr.straight_line(tiago.problem, tiago.axis(1)).value, 2) == 27.42


# ----- 4. where tipping begins -----


@pytest.mark.parametrize(
    ("name", "reading", "k", "sign"),
    [("tiago", "straight_line", 0, 1.0), ("tiago", "straight_line", 0, -1.0), ("paper0", "support", 0, 1.0)],
)
def test_no_tip_maximum_lifts_a_support_and_puts_the_zmp_on_the_edge(request, name, reading, k, sign):
    """Below the ideal maximum, the no-tip maximum is where the ZMP reaches the support polygon's
    edge: every contact off that edge carries no load (if the ZMP were strictly inside, the
    maximiser would be a local, hence global, maximum of the ideal LP)."""
    case = request.getfixturevalue(name)
    P, e = case.problem, case.axis(k, sign)
    read = getattr(fr, reading)
    grounded = read(P, e, mode="no_tip")
    assert grounded.value < read(P, e).value - 1e-3
    weight = P.total_mass * fr.GRAVITY
    assert grounded.forces[:, 2].min() <= 1e-9 * weight
    assert abs(fr.polygon_margin(fr.support_polygon(P.points), grounded.zmp)) <= 1e-7


def test_ideal_maxima_put_the_zmp_outside_the_support(tiago, paper0):
    """Issue 24: the paper robot's +x maximum asks 5.2 kN of traction and puts the ZMP at x = -0.39 m
    (support +-0.25 m); TIAGo++'s at x = -0.60 m (support -0.19 to +0.15 m). Every ideal maximiser
    tips: the no-tip maximum is lower (previous test)."""
    paper = fr.support(paper0.problem, EX)
    assert round(paper.zmp[0], 2) == -0.39
    assert round(paper.forces[:, 0].sum() / 1000.0, 1) == 5.2
    assert fr.polygon_margin(fr.support_polygon(paper0.problem.points), paper.zmp) < 0.0
    tiago_max = fr.straight_line(tiago.problem, tiago.axis(0))
    assert round(tiago_max.zmp[0], 2) == -0.60
    polygon = fr.support_polygon(tiago.problem.points)
    assert (round(polygon[:, 0].min(), 2), round(polygon[:, 0].max(), 2)) == (-0.19, 0.15)
    assert fr.polygon_margin(polygon, tiago_max.zmp) < 0.0


def test_zero_moment_point_and_margin_by_hand():
    points = np.array([[0.0, 0.0, -0.1], [1.0, 0.0, -0.1], [1.0, 2.0, -0.1], [0.0, 2.0, -0.1]])
    up = np.array([[0.0, 0.0, 1.0]] * 4)
    np.testing.assert_allclose(fr.zero_moment_point(points, up), (0.5, 1.0, -0.1))
    np.testing.assert_allclose(fr.zero_moment_point(points, up * [[0], [0], [1], [3]]), (0.25, 2.0, -0.1))
    # A horizontal force applied at the floor adds no moment about a floor point: the ZMP stays put.
    np.testing.assert_allclose(fr.zero_moment_point(points, up + [[5.0, -2.0, 0.0]] * 4), (0.5, 1.0, -0.1))
    polygon = fr.support_polygon(points)
    assert fr.polygon_margin(polygon, (0.5, 1.0)) == pytest.approx(0.5)
    assert fr.polygon_margin(polygon, (-0.3, 1.0)) == pytest.approx(-0.3)
    assert fr.polygon_margin(polygon, (1.0, 1.0)) == pytest.approx(0.0)
