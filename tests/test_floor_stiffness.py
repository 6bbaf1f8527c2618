"""Contacts of unequal stiffness (sprung casters, soft tyres): the spec's ``[support.stiffness]``
decides how the compliant floor shares the weight.

Under a rigid platform every contact is a spring: its deflection is an affine function of its
floor position and its normal force that deflection times its stiffness. Checked against the
independent whole-robot LP (tests/floor_reference.py, normal_c = k_c (a + b x_c + c y_c) with
a, b, c unknowns), against the closed form of a rigid plate on springs standing still, and for
the properties the model must have (only the ratios of the stiffnesses matter; equal ones are
the default model; a stiffer contact carries more).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import mobmanip
from floor_reference import PAPER_CASTERS, build_problem, straight_line, support
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.errors import SpecError
from mobmanip.postures.named import named_configuration
from mobmanip.robot.support import Support, robot_support
from mobmanip.robot.support_spec import SupportSpec, support_spec_from_table
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor, compliant_sharing, ground_reaction

MASS = 2.0


def _stiff(base: Support, stiffness: dict[str, float]) -> Support:
    contacts = tuple(dataclasses.replace(c, stiffness=stiffness.get(c.name, 1.0)) for c in base.contacts)
    return dataclasses.replace(base, contacts=contacts)


def _cases():
    tiago = mobmanip.load_robot("tiago_dual")
    yield "tiago_dual hold", tiago, named_configuration(tiago, "hold"), "spatial", None
    paper = mobmanip.load_robot("planar_dual_arm")
    yield "paper 0 deg", paper, configuration_at(paper, optimal_posture(paper), 0.0), "planar", PAPER_CASTERS


CASES = {name: case for name, *case in _cases()}


def _soft_casters(support: Support) -> dict[str, float]:
    """Every passive support softer than the wheels, each by its own factor."""
    passive = [c.name for c in support.contacts if not c.driven]
    return {name: 0.25 + 0.3 * k for k, name in enumerate(passive)}


@pytest.mark.parametrize("mu", [None, 0.5])
@pytest.mark.parametrize("case", list(CASES))
def test_reaches_with_unequal_springs_equal_the_independent_lp(case, mu):
    robot, q, task, casters = CASES[case]
    base = robot_support(robot)
    stiffness = _soft_casters(base)
    floor = Floor(mu=mu, load="compliant", support=_stiff(base, stiffness))
    analysis = mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(floor,))
    P = analysis.measures["dynamic_polytope"]
    problem = build_problem(robot, q, task, analysis.held_object, casters=casters)
    # the reference's contacts, matched to mobmanip's by their floor positions
    mine = {tuple(np.round(c["point"][:2], 9)): c["name"] for c in P.model["floor"]["contacts"]}
    names = [mine[tuple(np.round(p[:2], 9))] for p in problem.points]
    k = np.array([stiffness.get(name, 1.0) for name in names])
    assert len(set(k)) > 2  # the springs really differ
    mode = "no_tip" if mu is None else "friction"
    m = P.dim
    directions = np.vstack([np.eye(m)[: min(m, 3)], -np.eye(m)[: min(m, 3)]])
    for e in directions:
        line = straight_line(problem, e, mode=mode, mu=mu, springs=k).value
        top = support(problem, e, mode=mode, mu=mu, springs=k).value
        assert P.straight_line_reach(e) == pytest.approx(line, rel=1e-6, abs=1e-9), e
        assert P.support(e) == pytest.approx(top, rel=1e-6, abs=1e-9), e
        # and the normal forces at the maximum are the springs' (k times an affine deflection)
        reaction = ground_reaction(P.model["floor"], P.straight_line_witness(e).variables[CONTACT_FORCES])
        normals = np.array([reaction["contacts"][c["name"]]["normal"] for c in P.model["floor"]["contacts"]])
        springs = np.array([c["stiffness"] for c in P.model["floor"]["contacts"]])
        points = np.array([c["point"][:2] for c in P.model["floor"]["contacts"]])
        fit = np.column_stack([np.ones(len(points)), points])
        deflection = normals / springs
        residual = deflection - fit @ np.linalg.lstsq(fit, deflection, rcond=None)[0]
        assert np.abs(residual).max() <= 1e-7 * np.abs(deflection).max(), e


def test_only_the_ratios_matter_and_equal_springs_are_the_default():
    robot, q, task, _ = CASES["tiago_dual hold"]
    base = robot_support(robot)
    soft = _soft_casters(base)

    def reach(support):
        P = mobmanip.analyze(
            robot, q, task, object_mass=MASS, measures=("dynamic_polytope",),
            constraints=(Floor(mu=0.5, support=support),),
        ).measures["dynamic_polytope"]  # fmt: skip
        return np.array([P.straight_line_reach(e) for e in np.vstack([np.eye(6)[:2], -np.eye(6)[:2]])])

    default, equal = reach(None), reach(_stiff(base, dict.fromkeys(base.names, 7.0)))
    np.testing.assert_allclose(equal, default, rtol=1e-9)
    scaled = {name: 3.0 * soft.get(name, 1.0) for name in base.names}
    np.testing.assert_allclose(reach(_stiff(base, scaled)), reach(_stiff(base, soft)), rtol=1e-7)
    assert not np.allclose(reach(_stiff(base, soft)), default, rtol=1e-3)  # and the springs do matter


def test_standing_still_the_springs_share_as_a_rigid_plate_does():
    """A plate on springs k_c at (x_c, y_c) under a weight W at (x_g, y_g): the deflection
    d = a + b x + c y solves sum k d = W, sum k d x = W x_g, sum k d y = W y_g. The sharing rows
    with the balance's three give the same normal forces, for a square and an irregular support."""
    rng = np.random.default_rng(4)
    for points in (np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]), rng.uniform(-1, 1, (6, 2))):
        k = rng.uniform(0.2, 3.0, len(points))
        W, g = 100.0, np.array([0.1, -0.05])
        plate = np.column_stack([np.ones(len(points)), points])
        abc = np.linalg.solve(plate.T @ (k[:, None] * plate), W * np.r_[1.0, g])
        want = k * (plate @ abc)
        N = compliant_sharing(points, k)
        assert N.shape == (len(points) - 3, len(points))
        np.testing.assert_allclose(N @ N.T, np.eye(len(N)), atol=1e-12)
        system = np.vstack([np.ones(len(points)), points.T, N])
        got = np.linalg.solve(system, np.r_[W, W * g, np.zeros(len(N))])
        np.testing.assert_allclose(got, want, rtol=1e-10)
        if len(points) != 4:
            continue
        assert np.all(got > 0)
        stiffer = k.copy()
        stiffer[0] *= 4.0  # on the square, loaded everywhere: a stiffer contact carries more
        got_stiffer = np.linalg.solve(np.vstack([np.ones(len(points)), points.T, compliant_sharing(points, stiffer)]),
                                      np.r_[W, W * g, np.zeros(len(N))])  # fmt: skip
        assert got_stiffer[0] > got[0]


def test_the_spec_table_and_its_errors():
    spec = support_spec_from_table({"stiffness": {"caster_0": 0.4, "wheel_left_joint": 2}}, "robot.toml")
    assert spec.stiffness == {"caster_0": 0.4, "wheel_left_joint": 2.0}
    for bad in (0, -1.0, float("nan"), True, "soft"):
        with pytest.raises(SpecError, match=r"\[support\] stiffness of 'caster_0' must be a finite number > 0"):
            SupportSpec(stiffness={"caster_0": bad})
    with pytest.raises(SpecError, match="stiffness must be a table"):
        support_spec_from_table({"stiffness": [1, 2]}, "robot.toml")
    robot = mobmanip.load_robot("tiago_dual")

    def with_stiffness(table):
        spec = dataclasses.replace(robot.spec, support=SupportSpec(stiffness=table))
        return dataclasses.replace(robot, spec=spec)

    listed = "'no_such_caster'.*not among tiago_dual's contacts: wheel_right_joint, wheel_left_joint, caster_front"
    with pytest.raises(SpecError, match=listed):
        robot_support(with_stiffness({"no_such_caster": 0.5}))
    last = robot_support(robot).names[-1]
    named = robot_support(with_stiffness({last: 0.5}))
    assert named.stiffness.tolist() == [1.0] * (len(named.names) - 1) + [0.5]
    assert named.to_dict()["contacts"][-1]["stiffness"] == 0.5


def test_the_traction_along_a_motion_shares_by_the_springs_too():
    """trajectory --ground reads each sample's normal forces from the floor's resultant: with
    unequal springs they are the rigid plate's (closed form above), not the equal springs'."""
    from mobmanip.motion.traction import contact_forces

    points = np.array([[0.3, 0.25], [0.3, -0.25], [-0.3, 0.25], [-0.3, -0.25], [0.0, 0.3], [0.0, -0.3]])
    driven = np.array([False, False, False, False, True, True])
    k = np.array([0.3, 0.5, 0.7, 0.9, 1.0, 1.0])
    force, zmp = np.array([5.0, -3.0, 400.0]), np.array([0.04, -0.02])
    moment = np.array([0.0, 0.0, 1.5])
    plate = np.column_stack([np.ones(len(points)), points])
    want = k * (plate @ np.linalg.solve(plate.T @ (k[:, None] * plate), force[2] * np.r_[1.0, zmp]))
    normal, tangential, use = contact_forces(points, driven, force, moment, zmp, 0.5, k)
    np.testing.assert_allclose(normal, want, rtol=1e-10)
    equal, _, _ = contact_forces(points, driven, force, moment, zmp, 0.5)
    assert np.abs(equal - normal).max() > 1.0  # newtons: the springs change the sharing
    np.testing.assert_allclose(tangential.sum(axis=0), force[:2], atol=1e-9)


def test_mujoco_with_the_same_springs_shares_the_weight_as_predicted():
    """MuJoCo (tests/mujoco_referee.py) with each contact's softness divided by its stiffness:
    the efforts of grounded maxima of TIAGo++ (97 %, the calm witness) give every contact the
    normal force mobmanip predicts, within 0.1 % of the weight, and the object the predicted
    acceleration within 3 %; with equal springs the same efforts load the contacts otherwise."""
    pytest.importorskip("mujoco")
    from mujoco_referee import build, urdf_casters

    robot, q, task, _ = CASES["tiago_dual hold"]
    base = robot_support(robot)
    stiffness = _soft_casters(base)
    floor = Floor(mu=0.5, support=_stiff(base, stiffness))
    analysis = mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(floor,))
    P = analysis.measures["dynamic_polytope"]
    casters = urdf_casters(robot)
    # the referee's names for mobmanip's contacts (matched by their points in the root frame)
    theirs = {name: name for name in robot.platform.drive_names}
    for contact in base.contacts:
        if not contact.driven:
            theirs[contact.name] = min(casters, key=lambda n: np.linalg.norm(casters[n][:2] - contact.point[:2]))
            assert np.linalg.norm(casters[theirs[contact.name]][:2] - contact.point[:2]) < 1e-9
    springs = {theirs[name]: value for name, value in stiffness.items()}
    referee = build(robot, q, support_points=casters, object=analysis.held_object, mu=0.5, stiffness=springs)
    equal = build(robot, q, support_points=casters, object=analysis.held_object, mu=0.5)
    names = [c["name"] for c in P.model["floor"]["contacts"]]
    apart = 0.0
    for e in (np.eye(6)[0], -np.eye(6)[0], np.eye(6)[1]):
        target = 0.97 * P.straight_line_reach(e) * e
        w = P.witness_at(target, least="xdot")
        reaction = ground_reaction(P.model["floor"], w.variables[CONTACT_FORCES])
        predicted = np.array([reaction["contacts"][name]["normal"] for name in names])
        acc, contacts = referee.forward(w.variables["tau"])
        scale = np.maximum(np.abs(target), 0.03 * np.linalg.norm(target))
        assert np.all(np.abs(acc - target) <= 0.03 * scale), (e, acc, target)
        measured = np.array([contacts[theirs[name]].normal for name in names])
        assert np.abs(measured - predicted).max() <= 1e-3 * referee.weight, (e, measured, predicted)
        _, contacts_equal = equal.forward(w.variables["tau"])
        others = np.array([contacts_equal[theirs[name]].normal for name in names])
        apart = max(apart, np.abs(others - predicted).max())
    assert apart > 0.02 * referee.weight, apart / referee.weight  # the springs change how MuJoCo shares it too
