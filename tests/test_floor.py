"""Grounded capacity (issue 24): mobmanip's floor constraint against an independent reference.

mobmanip writes the robot on the floor as its reduced dynamics plus the whole robot's
Newton-Euler rows from Pinocchio's centroidal map of its own (planar-root) model
(:mod:`mobmanip.terms.constraints.floor`). The reference (tests/floor_reference.py) rebuilds
the robot from its URDF with a free-flyer root and writes the full floating-base dynamics with
contact Jacobians, solved by scipy's linprog: two different formulations of one physics. They
must agree to 1e-6 relative on TIAGo++ (hold, 2 kg, spatial) and on the paper robot (0 and 90
deg, planar), for every model of the floor, both readings (support and straight-line reach) and
both policies (any internal force, the paper's minimum-norm one).
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from floor_reference import PAPER_CASTERS, build_problem, equilibrium, straight_line, support
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.errors import MobmanipError, SpecError
from mobmanip.postures.named import named_configuration
from mobmanip.robot.support import ContactPoint, Support, robot_support
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor, ground_reaction

MASS = 2.0
FLOORS = {"no_tip": (None, "no_tip"), "mu=0.5": (0.5, "friction"), "mu=1.0": (1.0, "friction")}
MEASURES = {"dynamic_polytope": False, "dynamic_polytope_min_norm": True}
LOADS = {"compliant": True, "any": False}  # the floor's load sharing -> the reference's springs


def _cases():
    tiago = mobmanip.load_robot("tiago_dual")
    yield "tiago_dual hold", tiago, named_configuration(tiago, "hold"), "spatial", None
    paper = mobmanip.load_robot("planar_dual_arm")
    posture = optimal_posture(paper)
    for angle in (0.0, 90.0):
        yield f"paper {angle:g} deg", paper, configuration_at(paper, posture, angle), "planar", PAPER_CASTERS


CASES = {name: case for name, *case in _cases()}


def _directions(m: int) -> np.ndarray:
    if m == 2:
        return np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0], [0.6, 0.8], [-0.8, 0.6]])
    axes = np.eye(m)[:3]  # the linear axes of a spatial task, both senses, and a mixed direction
    mixed = np.ones(m) / np.sqrt(m)
    return np.vstack([axes, -axes, mixed])


@pytest.mark.parametrize("load", list(LOADS))
@pytest.mark.parametrize("floor", list(FLOORS))
@pytest.mark.parametrize("case", list(CASES))
def test_grounded_reaches_equal_the_independent_lp(case, floor, load):
    robot, q, task, casters = CASES[case]
    mu, mode = FLOORS[floor]
    springs = LOADS[load]
    analysis = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=tuple(MEASURES), constraints=(Floor(mu=mu, load=load),)
    )  # fmt: skip
    problem = build_problem(robot, q, task, analysis.held_object, casters=casters)
    for name, policy in MEASURES.items():
        grounded = analysis.measures[name]
        for e in _directions(grounded.dim):
            e = e / np.linalg.norm(e)
            ref_line = straight_line(problem, e, mode=mode, mu=mu, policy=policy, springs=springs).value
            ref_support = support(problem, e, mode=mode, mu=mu, policy=policy, springs=springs).value
            assert grounded.straight_line_reach(e) == pytest.approx(ref_line, rel=1e-6, abs=1e-9), (name, e)
            assert grounded.support(e) == pytest.approx(ref_support, rel=1e-6, abs=1e-9), (name, e)


@pytest.mark.parametrize(
    "case, reserve",
    [("tiago_dual hold", 0.1), ("paper 90 deg", 0.1), ("tiago_dual hold", 0.3), ("paper 0 deg", 0.3),
     ("paper 90 deg", 0.3)],
)  # fmt: skip
def test_a_reserve_equals_the_independent_lp_and_keeps_its_margins(case, reserve):
    """With a reserve r every support keeps r of its equal share of the weight and every wheel
    uses at most 1 - r of its pyramid: the reaches equal the reference's with the same margins
    (1e-6), and at each maximum the contact forces keep them. (0.3: the reserve whose maxima hold
    for 20 ms in MuJoCo on every axis, tests/test_floor_physics.py.)"""
    robot, q, task, casters = CASES[case]
    analysis = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, reserve=reserve),)
    )
    problem = build_problem(robot, q, task, analysis.held_object, casters=casters)
    P = analysis.measures["dynamic_polytope"]
    weight = problem.total_mass * 9.81
    for e in _directions(P.dim)[:4] if reserve == 0.1 else _directions(P.dim):
        e = e / np.linalg.norm(e)
        ref = straight_line(problem, e, mode="friction", mu=0.5, springs=True, reserve=reserve).value
        assert P.straight_line_reach(e) == pytest.approx(ref, rel=1e-6), e
        floor = ground_reaction(P.model["floor"], P.straight_line_witness(e).variables[CONTACT_FORCES])
        normals = [c["normal"] for c in floor["contacts"].values()]
        assert min(normals) >= reserve * weight / len(normals) * (1 - 1e-7)
        uses = [c["traction_use"] for c in floor["contacts"].values() if c.get("traction_use") is not None]
        assert max(uses) <= (1 - reserve) * (1 + 1e-7)  # the pyramid's faces are inside 1 - r of the cone


def test_the_least_motion_witness_reaches_the_point_with_less_motion():
    """witness_at(p, least="xdot") reaches p with at least half the greatest slack and a 1-norm
    of the reduced accelerations no larger than the most-slack witness's."""
    robot, q, task, _ = CASES["tiago_dual hold"]
    P = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    ).measures["dynamic_polytope"]
    target = 0.9 * P.straight_line_reach(-np.eye(6)[0]) * -np.eye(6)[0]
    wide, calm = P.witness_at(target), P.witness_at(target, least="xdot")
    assert np.allclose(calm.point, target, atol=1e-9) and np.allclose(wide.point, target, atol=1e-9)
    assert np.abs(calm.variables["xdot"]).sum() <= np.abs(wide.variables["xdot"]).sum() + 1e-9
    floor = ground_reaction(P.model["floor"], calm.variables[CONTACT_FORCES])
    assert min(c["normal"] for c in floor["contacts"].values()) > 0.0
    with pytest.raises(MobmanipError, match="least must name one of the set's variables"):
        P.witness_at(target, least="nothing")


def test_the_efforts_of_a_maximum_itself_are_found_on_every_axis():
    """witness_at at the straight-line maximum itself, where no row has slack: the efforts it
    returns (the least-motion ones) drive the closed chain, solved on its own, to that point.
    With a reserve of 0.1, TIAGo++'s -pitch maximum once left HiGHS at 'Unknown'."""
    from mobmanip.motion.hold import forward_accelerations
    from mobmanip.motion.in_motion import motion_terms

    robot, q, task, _ = CASES["tiago_dual hold"]
    P = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, reserve=0.1),)
    ).measures["dynamic_polytope"]
    terms = motion_terms(robot, q, np.zeros(robot.nx), task, object_mass=MASS)
    for e in np.vstack([np.eye(6), -np.eye(6)]):
        top = P.straight_line_reach(e) * e
        tau = P.witness_at(top, least="xdot").variables["tau"]
        assert np.all(np.abs(tau) <= robot.effort_limits * (1 + 1e-9))
        np.testing.assert_allclose(forward_accelerations(terms, tau)[2], top, atol=1e-7 * np.abs(top).max())


def test_an_empty_grounded_set_has_no_witness():
    """The paper robot holding 10 kg at home: its compliant set is empty (the centre of mass is
    outside the four casters' core), so no efforts reach even rest: witness_at says the point is
    not in the set (it raised an AttributeError: an empty set had no size for its tolerance)."""
    robot = mobmanip.load_robot("planar_dual_arm")
    P = mobmanip.analyze(
        robot, named_configuration(robot, "home"), "planar", object_mass=10.0, measures=("dynamic_polytope",),
        constraints=(Floor(mu=0.5, level=True),),
    ).measures["dynamic_polytope"]  # fmt: skip
    assert P.empty
    for least in (None, "xdot"):
        with pytest.raises(MobmanipError, match=r"the point \[0.0, 0.0\] is not in the set"):
            P.witness_at(np.zeros(2), least=least)


def test_compliant_normals_are_an_affine_function_of_the_contacts_positions():
    """At every compliant maximum the normal forces lie on a plane over the contacts' floor
    positions (equally stiff springs under a rigid base), and the sharing 'any' leaves it."""
    robot, q, task, _ = CASES["tiago_dual hold"]
    for load, affine in (("compliant", True), ("any", False)):
        P = mobmanip.analyze(
            robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, load=load),)
        ).measures["dynamic_polytope"]
        floor = ground_reaction(P.model["floor"], P.straight_line_witness(np.eye(6)[0]).variables[CONTACT_FORCES])
        points = np.array([c["point"][:2] for c in P.model["floor"]["contacts"]])
        normals = np.array([c["normal"] for c in floor["contacts"].values()])
        fit = np.column_stack([np.ones(len(points)), points])
        residual = normals - fit @ np.linalg.lstsq(fit, normals, rcond=None)[0]
        assert (np.abs(residual).max() < 1e-6 * normals.sum()) == affine, (load, residual)


#: The issue table's columns: no floor, no tip-over alone, and tip-over with friction.
ISSUE_FLOORS = {
    "ideal": (),
    "no_tip": (Floor(mu=None, level=True),),
    "mu=0.5": (Floor(mu=0.5, load="any", level=True),),
}


def test_the_issue_table_in_numbers():
    """Issue 24's table (measured with an LP of this kind, any sharing of the load), at its
    printed rounding."""
    robot, q, task, _ = CASES["tiago_dual hold"]
    reach = {}
    for label, floor in ISSUE_FLOORS.items():
        P = mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=floor)
        e = np.eye(6)[0]
        reach[label] = (
            P.measures["dynamic_polytope"].straight_line_reach(e),
            P.measures["dynamic_polytope"].straight_line_reach(-e),
        )
    assert [round(v, 2) for v in reach["ideal"]] == [48.65, 47.51]
    assert [round(v, 2) for v in reach["no_tip"]] == [38.89, 32.25]
    assert [round(v, 2) for v in reach["mu=0.5"]] == [37.08, 27.87]
    paper, q0, _, _ = CASES["paper 0 deg"]
    policy = {}
    for label, floor in ISSUE_FLOORS.items():
        P = mobmanip.analyze(
            paper, q0, "planar", object_mass=MASS, measures=("dynamic_polytope_min_norm",), constraints=floor
        )
        policy[label] = [P.measures["dynamic_polytope_min_norm"].straight_line_reach(e) for e in ([0, 1.0], [0, -1.0])]
    assert [round(v, 2) for v in policy["ideal"]] == [30.25, 30.25]
    assert [round(v, 2) for v in policy["no_tip"]] == [30.25, 30.25]
    assert all(round(v, 1) in (4.3, 4.4) for v in policy["mu=0.5"])  # "4.3 (7x lower)"


def test_what_stops_it_no_tip_maximum_lifts_a_contact_with_the_zmp_on_the_edge():
    robot, q, task, _ = CASES["tiago_dual hold"]
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=None),)
    )
    P = grounded.measures["dynamic_polytope"]
    for e in (np.eye(6)[0], -np.eye(6)[0]):
        w = P.straight_line_witness(e)
        report = ground_reaction(P.model["floor"], w.variables[CONTACT_FORCES])
        assert any("lifts off the floor" in b for b in w.binding)
        assert report["margin"] == pytest.approx(0.0, abs=1e-7)
        normals = [c["normal"] for c in report["contacts"].values()]
        assert min(normals) == pytest.approx(0.0, abs=1e-6) and min(normals) >= -1e-6
    # the ideal maximiser along +x puts the ZMP behind the support (issue: x = -0.60 m, support
    # -0.19 .. 0.15 m): the floor would have to pull on the front casters
    free = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(lift=True),)
    )
    ideal = free.measures["dynamic_polytope"]
    w = ideal.straight_line_witness(np.eye(6)[0])
    assert w.value == pytest.approx(48.65, abs=0.005)
    report = ground_reaction(ideal.model["floor"], w.variables[CONTACT_FORCES])
    assert report["zmp"][0] == pytest.approx(-0.60, abs=0.005)
    assert report["margin"] < -0.4


def test_newton_holds_at_a_grounded_maximum():
    """At the mu = 0.5 maximum along +x, the floor's total force equals the robot's momentum rate
    (from Pinocchio's centre-of-mass Jacobian, not the centroidal map the constraint uses) minus
    its weight plus what the hands push on the object; every wheel within its cone."""
    import pinocchio as pin

    robot, q, task, _ = CASES["tiago_dual hold"]
    analysis = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    )
    P = analysis.measures["dynamic_polytope"]
    w = P.straight_line_witness(np.eye(6)[0])
    xdot, h, forces = w.variables["xdot"], w.variables["h"].reshape(-1, 6), w.variables[CONTACT_FORCES]
    data = robot.model.createData()
    J_com = pin.jacobianCenterOfMass(robot.model, data, q)
    mass = pin.computeTotalMass(robot.model)
    com_acc = J_com @ robot.null_space(q) @ xdot
    total = np.zeros(3)
    for contact in P.model["floor"]["contacts"]:
        a, b = contact["columns"]
        f = np.zeros(3)
        f[3 - (b - a) :] = forces[a:b]
        total += f
        if contact["driven"]:
            assert np.hypot(f[0], f[1]) <= 0.5 * f[2] + 1e-6
    expected = mass * com_acc + mass * np.array([0.0, 0.0, 9.81]) + h[:, :3].sum(axis=0)
    np.testing.assert_allclose(total, expected, atol=1e-6 * np.abs(expected).max())
    # and the object: the hands' forces give its acceleration against its weight
    np.testing.assert_allclose(h[:, :3].sum(axis=0), MASS * (w.point[:3] + np.array([0.0, 0.0, 9.81])), atol=1e-6)


def test_support_errors_name_the_contact_and_the_value():
    robot = mobmanip.load_robot("planar_dual_arm")
    s = robot_support(robot)
    assert [c.name for c in s.contacts][:2] == ["wheel_right_joint", "wheel_left_joint"]
    wheels = s.contacts[:2]
    with pytest.raises(SpecError, match="at least three contacts not on one line.*wheel_right_joint, wheel_left_joint"):
        Support(wheels, s.floor_z)
    above = ContactPoint("caster_x", np.array([0.2, 0.0, s.floor_z + 0.01]), False, "spec")
    with pytest.raises(SpecError, match=r"'caster_x' at z = -0.065 m lies 0.01 m above the floor"):
        Support((*wheels, above), s.floor_z)
    millimetres = ContactPoint("caster_mm", np.array([250.0, 140.0, s.floor_z]), False, "spec")
    with pytest.raises(SpecError, match=r"'caster_mm' at \(250, 140\) m lies 287 m from the platform's origin"):
        Support((*wheels, millimetres), s.floor_z)
    with pytest.raises(SpecError, match=r"mu must be a finite friction coefficient >= 0, got -0.2"):
        Floor(mu=-0.2)
    with pytest.raises(SpecError, match="faces must be an integer from 3 to 64, got 2"):
        Floor(mu=0.5, faces=2)
    fixed = mobmanip.load_robot("ur5")
    with pytest.raises(MobmanipError, match="covers platforms that move on the floor .*'ur5' has a fixed platform"):
        mobmanip.analyze(fixed, fixed.neutral(), measures=("dynamic_polytope",), constraints=(Floor(),))


def test_a_badly_scaled_posture_still_solves():
    """The paper robot with both arms stretched sideways (where `site` placed it): the warm-started
    program stalled there ("Not Set") until a cold restart; the reach equals the reference's."""
    robot = mobmanip.load_robot("planar_dual_arm")
    q = np.array(
        [
            0.9999963453751275,
            1.9999999999167972,
            0.9999999975922588,
            -6.939367724042154e-05,
            -1.5707320681565353,
            -2.0474306146860132e-06,
            2.6809227779099436e-05,
            -1.5707320637879132,
            -2.0656362182882284e-06,
            2.6832533120518905e-05,
            1.0,
            0.0,
            1.0,
            0.0,
        ]
    )  # place's optimum for an object at (1, 0.5, 0.35), +x
    analysis = mobmanip.analyze(
        robot,
        q,
        "planar",
        object_mass=MASS,
        measures=("dynamic_polytope",),
        constraints=(Floor(mu=0.5, load="any", level=True),),
    )
    problem = build_problem(robot, q, "planar", analysis.held_object, casters=PAPER_CASTERS, level=True)
    P = analysis.measures["dynamic_polytope"]
    for e in _directions(2):
        e = e / np.linalg.norm(e)
        ref = straight_line(problem, e, mode="friction", mu=0.5).value
        assert P.straight_line_reach(e) == pytest.approx(ref, rel=1e-6, abs=1e-9)
    # With equally stiff contacts the robot cannot even stand still there: the reference's LP with
    # springs is infeasible, and held still with pulling allowed its springs pull on the contact the
    # warning names.
    compliant = mobmanip.analyze(
        robot, q, "planar", object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, level=True),)
    )
    assert compliant.measures["dynamic_polytope"].empty
    with pytest.raises(RuntimeError, match="infeasible"):
        equilibrium(problem, mode="friction", mu=0.5, springs=True)
    still = equilibrium(problem, mode="ideal", springs=True)
    pulled = [c.name for c, f in zip(problem.contacts, still.forces) if f[2] < 0.0]
    (warning,) = [w for w in compliant.warnings if "on the floor is empty" in w]
    assert pulled and f"would unload {', '.join(pulled)} (" in warning
