"""Teams of robots holding one object: the team's sets against independent references.

References here are built from Pinocchio and the defining equations (joint boxes, the grasp's
rigid-body blocks, the robots' equations of motion), never from mobmanip's team code.
"""

from __future__ import annotations

import math
from pathlib import Path

import highspy
import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from ellipsoid_reference import dynamic_ellipsoid_closed_form
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.team import Member, Team, team_from_dict
from mobmanip.team.analysis import analyze_team, ray_radius
from polytope_util import SupportLP

ALL = ("kinematic", "dynamic", "kinematic_polytope", "dynamic_polytope")
RIGID = (0, 1, 5)  # planar_rigid: the rows of a 6-D twist it keeps


@pytest.fixture(scope="module")
def posture(robot):
    return optimal_posture(robot, grid=25, refinements=3)


def unit_directions(rng, n, m):
    d = rng.normal(size=(n, m))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def supports(task_set, d):
    return np.array([task_set.support(v) for v in d])


def paper_member(robot, posture, name, x, y, yaw, angle_deg=0.0):
    """A paper robot at (x, y, yaw) with both hands together at angle_deg from its heading."""
    q = configuration_at(robot, posture, angle_deg, heading=yaw)
    q[:2] = (x, y)
    return Member(name, robot, q, (0, 1))


def mirrored(robot, member: Member, name: str) -> Member:
    """The mirror image of a paper robot about the world's x-z plane (y -> -y): platform pose
    (x, -y, -yaw), the right arm taking the left arm's joints negated and vice versa."""
    pose = robot.configuration_dict(member.q)
    x, y, yaw = pose["platform"]
    joints = pose["joints"]
    right, left = robot.arms
    new = {}
    for a, b in ((right, left), (left, right)):
        for ja, jb in zip(a.joint_names, b.joint_names):
            new[ja] = -joints[jb]
    return Member(name, robot, robot.configuration((x, -y, -yaw), new), (0, 1))


# ----------------------------------------------------------------------------------------------
# independent references


def grasp_block_rigid(r):
    """W_i for planar_rigid (rows x, y, yaw): force passes, moment about z = r_x f_y - r_y f_x."""
    return np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-r[1], r[0], 1.0]])


def pinocchio_blocks(member: Member, rows, gravity=True):
    """J_i S_i (grasping hands), P_i = S^T M S, xi_i = -S^T g, straight from Pinocchio."""
    robot, q = member.robot, member.q
    model, data = robot.model, robot.model.createData()
    S = robot.null_space(q)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    g = pin.computeGeneralizedGravity(model, data, q)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    J = []
    hands = []
    for a in member.arms:
        frame = robot.arms[a].frame_id
        J.append(pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)[list(rows)])
        hands.append(data.oMf[frame].translation.copy())
    return np.vstack(J) @ S, S.T @ M @ S, -S.T @ g, np.array(hands)


def independent_kinematic_support(members, center):
    """max d . v_o over (x_1, ..., x_k, v_o): J_i x_i = W_i^T v_o, |x_i| <= xdot_max_i."""
    blocks, Ws, lims = [], [], []
    for mem in members:
        J, _, _, hands = pinocchio_blocks(mem, RIGID)
        blocks.append(J)
        Ws.append(np.hstack([grasp_block_rigid(p - center) for p in hands]))
        lims.append(mem.robot.velocity_limits)
    rows = sum(b.shape[0] for b in blocks)
    cols = sum(b.shape[1] for b in blocks)
    A = np.zeros((rows, cols + 3))
    r = c = 0
    for J, W in zip(blocks, Ws):
        A[r : r + J.shape[0], c : c + J.shape[1]] = J
        A[r : r + J.shape[0], cols:] = -W.T
        r, c = r + J.shape[0], c + J.shape[1]
    lim = np.concatenate(lims)
    lo = np.r_[-lim, np.full(3, -np.inf)]
    return SupportLP(A, np.zeros(rows), lo, -lo, np.arange(cols, cols + 3))


# ----------------------------------------------------------------------------------------------
# a team of one is the robot's own analysis


def test_team_of_one_reproduces_analyze(robot, posture, rng):
    q = configuration_at(robot, posture, 25.0, heading=0.4)
    q[:2] = (0.3, -0.2)
    team = Team.holding([Member("solo", robot, q, (0, 1))], 3.0, task="planar_rigid")
    got = analyze_team(team, measures=ALL)
    ref = mobmanip.analyze(robot, q, "planar_rigid", object_mass=3.0, method="exact", measures=ALL)
    np.testing.assert_allclose(got.terms.J_u, ref.unified_jacobian, rtol=0, atol=1e-14)
    np.testing.assert_allclose(got.terms.W, ref.grasp_matrix, rtol=0, atol=1e-14)
    np.testing.assert_allclose(got.terms.P, ref.reduced_inertia, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.terms.xi, ref.bias, rtol=0, atol=1e-12)
    for name in ("kinematic", "dynamic"):
        a, b = got.measure(name), ref.measure(name)
        np.testing.assert_allclose(a.semi_axes, b.semi_axes, rtol=1e-12)
        np.testing.assert_allclose(a.center, b.center, rtol=0, atol=1e-12 * max(1.0, b.semi_axes[0]))
        np.testing.assert_allclose(a.matrix, b.matrix, rtol=1e-10, atol=1e-12 * np.abs(b.matrix).max())
    d = unit_directions(rng, 200, 3)
    for name in ("kinematic_polytope", "dynamic_polytope"):
        np.testing.assert_allclose(got.measure(name).supports(d), ref.measure(name).supports(d), rtol=1e-12)
    # and analyze's default (compiled) path, certified to 1e-9 of each ellipsoid's size
    fast = mobmanip.analyze(robot, q, "planar_rigid", object_mass=3.0)
    for name in ("kinematic", "dynamic"):
        a, b = got.measure(name), fast.measure(name)
        np.testing.assert_allclose(a.semi_axes, b.semi_axes, rtol=0, atol=1e-9 * b.semi_axes[0])
        np.testing.assert_allclose(a.center, b.center, rtol=0, atol=1e-9 * b.semi_axes[0])


def test_team_of_one_from_a_description_reproduces_analyze_in_space():
    """TIAGo++ in its hold posture, through the TOML path: object at the hands' centroid, no
    inertia given (the same default sphere as analyze's), spatial task."""
    tiago = mobmanip.load_robot("tiago_dual")
    q = tiago.hold_configuration()
    ref = mobmanip.analyze(tiago, q, "spatial", object_mass=2.0, method="exact")
    center = ref.held_object.center
    R = np.eye(3)
    data = {
        "task": "spatial",
        "object": {"mass": 2.0, "position": center.tolist()},
        "robots": [
            {
                "name": "t",
                "robot": "tiago_dual",
                "posture": "hold",
                "grasps": [
                    {"arm": arm.name, "point": (R.T @ off).tolist()}
                    for arm, off in zip(tiago.arms, ref.held_object.offsets)
                ],
            }
        ],
    }
    team = team_from_dict(data)
    got = analyze_team(team)
    for name in ("kinematic", "dynamic"):
        a, b = got.measure(name), ref.measure(name)
        np.testing.assert_allclose(a.semi_axes, b.semi_axes, rtol=1e-12)
        np.testing.assert_allclose(a.center, b.center, rtol=0, atol=1e-12 * max(1.0, b.semi_axes[0]))
        np.testing.assert_allclose(np.abs(a.axes @ b.axes.T), np.eye(6), atol=1e-9)


# ----------------------------------------------------------------------------------------------
# symmetry and order


@pytest.fixture(scope="module")
def mirror_team(robot, posture):
    a = paper_member(robot, posture, "a", 0.2, -1.9, math.radians(80.0), angle_deg=15.0)
    b = mirrored(robot, a, "b")
    return Team.holding([a, b], 4.0, task="planar_rigid")


def test_mirror_symmetric_robots_give_mirror_symmetric_sets(mirror_team, rng):
    an = analyze_team(mirror_team, measures=ALL)
    c = mirror_team.held_object.center
    assert abs(c[1]) < 1e-12  # the object's centre lies on the mirror plane
    M = np.diag([1.0, -1.0, -1.0])  # y -> -y turns the object's yaw rate over too
    d = unit_directions(rng, 300, 3)
    for name in ALL:
        s = an.measure(name)
        h = np.array([s.support(v) for v in d])
        h_mirror = np.array([s.support(v) for v in d @ M])
        np.testing.assert_allclose(h, h_mirror, rtol=1e-9, atol=1e-9 * np.abs(h).max(), err_msg=name)
    shares = an.contributions("kinematic", np.array([[1.0, 0.0, 0.0]]))
    np.testing.assert_allclose(shares[0], [0.5, 0.5], atol=1e-6)  # along the mirror plane: shared equally


def test_swapping_the_robots_changes_nothing(mirror_team, robot, posture, rng):
    a = paper_member(robot, posture, "a", 0.2, -1.9, math.radians(80.0), angle_deg=15.0)
    c = paper_member(robot, posture, "c", -0.3, 1.6, math.radians(-100.0), angle_deg=-30.0)
    d = unit_directions(rng, 300, 3)
    forward = analyze_team(Team.holding([a, c], 4.0, task="planar_rigid"), measures=ALL)
    backward = analyze_team(Team.holding([c, a], 4.0, task="planar_rigid"), measures=ALL)
    for name in ALL:
        s, t = forward.measure(name), backward.measure(name)
        np.testing.assert_allclose(supports(s, d), supports(t, d), rtol=1e-10, err_msg=name)
    e = np.eye(3)
    np.testing.assert_allclose(
        forward.contributions("kinematic_polytope", e),
        backward.contributions("kinematic_polytope", e)[:, ::-1],
        atol=1e-9,
    )
    assert forward.load_sharing(np.array([0.3, -0.2, 0.1])).worst == pytest.approx(
        backward.load_sharing(np.array([0.3, -0.2, 0.1])).worst, rel=1e-8
    )


# ----------------------------------------------------------------------------------------------
# two paper robots side by side: exact sets against linear programs, the dynamics from Pinocchio


@pytest.fixture(scope="module")
def side_by_side(robot, posture):
    a = paper_member(robot, posture, "right", 0.0, -0.45, 0.0, angle_deg=20.0)
    b = paper_member(robot, posture, "left", 0.0, 0.45, 0.0, angle_deg=-20.0)
    team = Team.holding([a, b], 5.0, task="planar_rigid", inertia=np.diag([0.05, 0.9, 0.9]))
    return team, analyze_team(team, measures=ALL)


def test_side_by_side_kinematic_set_equals_an_lp_over_both_joint_boxes(side_by_side, rng):
    team, an = side_by_side
    lp = independent_kinematic_support(team.members, team.held_object.center)
    d = unit_directions(rng, 1000, 3)
    reference = np.array([lp(v) for v in d])
    got = an.measure("kinematic_polytope").supports(d)
    np.testing.assert_allclose(got, reference, rtol=1e-7)
    # the stacked (Euclidean) ellipsoid lies inside the box-limited set
    ellipsoid = an.measure("kinematic")
    assert np.all(np.array([ellipsoid.support(v) for v in d]) <= reference * (1.0 + 1e-9))
    # and the exact set is the intersection of the robots' own sets
    own = [an.member_set("kinematic_polytope", i) for i in range(2)]
    for v in d[:50]:
        r = ray_radius(an.measure("kinematic_polytope"), v)
        assert r == pytest.approx(min(ray_radius(p, v) for p in own), rel=1e-9)


def test_side_by_side_dynamic_ellipsoid_equals_the_pinocchio_block_assembly(side_by_side):
    team, an = side_by_side
    obj = team.held_object
    Js, Ps, xis, Ws = [], [], [], []
    for mem in team.members:
        J, P, xi, hands = pinocchio_blocks(mem, RIGID)
        Js.append(J)
        Ps.append(P)
        xis.append(xi)
        Ws.extend(grasp_block_rigid(p - obj.center) for p in hands)
    import scipy.linalg

    J = scipy.linalg.block_diag(*Js)
    P = scipy.linalg.block_diag(*Ps)
    W = np.hstack(Ws)
    M_o = np.diag([obj.mass, obj.mass, obj.inertia[2, 2]])
    g_o = np.zeros(3)  # gravity has no component in the horizontal task
    tau_max = np.concatenate([m.robot.effort_limits for m in team.members])
    A, _, semi_axes = dynamic_ellipsoid_closed_form(J, W, P, np.eye(len(tau_max)), np.concatenate(xis), M_o, g_o,
                                                    tau_max)  # fmt: skip
    got = an.measure("dynamic")
    np.testing.assert_allclose(got.semi_axes, semi_axes, rtol=1e-10)
    np.testing.assert_allclose(got.matrix, A, rtol=1e-9, atol=1e-12 * np.abs(A).max())
    # the load matters: a massless object gives a larger set
    light = Team.holding(team.members, 0.0, task="planar_rigid")
    assert analyze_team(light).measure("dynamic").volume > got.volume


def test_kinematic_polytope_contributions_name_the_shortest_robot(side_by_side, rng):
    team, an = side_by_side
    d = unit_directions(rng, 40, 3)
    shares = an.contributions("kinematic_polytope", d)
    own = [an.member_set("kinematic_polytope", i) for i in range(2)]
    for v, row in zip(d, shares):
        radii = [ray_radius(p, v) for p in own]
        if abs(radii[0] - radii[1]) > 1e-3 * max(radii):
            expected = np.zeros(2)
            expected[int(np.argmin(radii))] = 1.0
            np.testing.assert_allclose(row, expected, atol=1e-9)
        elif abs(radii[0] - radii[1]) < 1e-12 * max(radii):  # a facet both robots share
            np.testing.assert_allclose(row, [0.5, 0.5], atol=1e-9)
    # velocity sets are homogeneous of degree one in the limits: the shares sum to one
    for name in ("kinematic", "kinematic_polytope"):
        for along in ("ray", "support"):
            np.testing.assert_allclose(an.contributions(name, d, along=along).sum(axis=1), 1.0, atol=1e-8)


def test_kinematic_ellipsoid_shares_follow_the_robots_quadratic_forms(side_by_side, rng):
    """Full-rank robots: A = A_1 + A_2, so along a ray the share of robot i is u^T A_i u / u^T A u."""
    _, an = side_by_side
    A = an.measure("kinematic").matrix
    A_i = [an.member_set("kinematic", i).matrix for i in range(2)]
    np.testing.assert_allclose(A, A_i[0] + A_i[1], rtol=1e-9, atol=1e-12 * np.abs(A).max())
    d = unit_directions(rng, 20, 3)
    expected = np.array([[v @ Ai @ v / (v @ A @ v) for Ai in A_i] for v in d])
    np.testing.assert_allclose(an.contributions("kinematic", d), expected, atol=1e-7)


# ----------------------------------------------------------------------------------------------
# load sharing


@pytest.fixture(scope="module")
def arms_team():
    ur5 = mobmanip.load_robot("ur5")
    joints = dict(zip(ur5.arms[0].joint_names, (0.0, -1.0, 1.2, -0.2, 1.57, 0.0)))
    other = dict(zip(ur5.arms[0].joint_names, (0.3, -1.3, 1.5, -0.4, 1.4, 0.2)))
    a = Member("a", ur5, ur5.configuration((0.0, 0.0, 0.0), joints), (0,))
    b = Member("b", ur5, ur5.configuration((1.2, 0.1, math.pi), other), (0,))
    return ur5, a, b


def spatial_block(r):
    W = np.eye(6)
    W[3:, :3] = [[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]]
    return W


def independent_worst(members, center, mass, inertia, a_o):
    """min over internal forces y of max_j |tau_j| / tau_max_j with h = h_0 + N y (N spans null(W)),
    tau = J^T h + G(q) (holding still) on HiGHS's interior-point solver."""
    import scipy.linalg

    Js, gs, Ws, lims = [], [], [], []
    for mem in members:
        J, _, xi, hands = pinocchio_blocks(mem, range(6))
        Js.append(J)
        gs.append(-xi)
        Ws.extend(spatial_block(p - center) for p in hands)
        lims.append(mem.robot.effort_limits)
    J = scipy.linalg.block_diag(*Js)
    W = np.hstack(Ws)
    M_o = np.zeros((6, 6))
    M_o[:3, :3] = mass * np.eye(3)
    M_o[3:, 3:] = inertia
    wrench = M_o @ a_o + np.r_[0.0, 0.0, 9.81 * mass, 0.0, 0.0, 0.0]
    h0 = np.linalg.lstsq(W, wrench, rcond=None)[0]
    N = scipy.linalg.null_space(W)
    Z = 1.0 / np.concatenate(lims)
    g = np.concatenate(gs)
    # Z (J^T (h0 + N y) + g) in [-t, t]
    T = Z[:, None] * (J.T @ N)
    c0 = Z * (J.T @ h0 + g)
    n = N.shape[1]
    h = highspy.Highs()
    h.silent()
    h.setOptionValue("solver", "ipm")
    inf = highspy.kHighsInf
    for _ in range(n):
        h.addVar(-inf, inf)
    h.addVar(0.0, inf)
    h.changeColCost(n, 1.0)
    for row, c in zip(T, c0):
        idx = np.arange(n + 1, dtype=np.int32)
        h.addRow(-inf, -c, n + 1, idx, np.r_[row, -1.0])
        h.addRow(-inf, c, n + 1, idx, np.r_[-row, -1.0])
    h.run()
    assert h.getModelStatus() == highspy.HighsModelStatus.kOptimal
    return h.getInfo().objective_function_value, W, wrench, J, g


@pytest.mark.parametrize("mass", [10.0, 80.0])
def test_load_sharing_balances_the_object_and_no_choice_does_better(arms_team, mass):
    _, a, b = arms_team
    team = Team.holding([a, b], mass, task="spatial")
    an = analyze_team(team)
    share = an.load_sharing()
    obj = team.held_object
    best, W, wrench, J, g = independent_worst(team.members, obj.center, mass, obj.inertia, np.zeros(6))
    h = share.wrenches.ravel()
    np.testing.assert_allclose(W @ h, wrench, rtol=0, atol=1e-10 * np.abs(wrench).max())
    tau = np.concatenate(share.torques)
    np.testing.assert_allclose(tau, J.T @ h + g, rtol=0, atol=1e-9 * np.abs(tau).max())
    limits = np.concatenate([m.robot.effort_limits for m in team.members])
    # the worst normalised torque of the reported wrenches, through the independent J and g
    assert share.worst == pytest.approx(np.max(np.abs(J.T @ h + g) / limits), rel=1e-9)
    assert share.worst == pytest.approx(best, rel=1e-7)
    assert share.empty == (best > 1.0)


def test_an_overload_is_flagged_empty(arms_team):
    _, a, b = arms_team
    team = Team.holding([a, b], 400.0, task="spatial")
    share = analyze_team(team).load_sharing()
    best = independent_worst(team.members, team.held_object.center, 400.0, team.held_object.inertia, np.zeros(6))[0]
    assert best > 1.0 and share.empty and share.worst == pytest.approx(best, rel=1e-7)
    light_team = analyze_team(Team.holding([a, b], 1.0, task="spatial"), ("dynamic_polytope",))
    light = light_team.load_sharing()
    assert not light.empty and light.worst < 1.0
    # each UR5's Jacobian is square and invertible: holding still forces qdd = 0, so the exact
    # dynamic set (any internal forces) holds a_o = 0 exactly when the load sharing fits
    heavy = analyze_team(team, ("dynamic_polytope",)).measure("dynamic_polytope")
    assert not heavy.contains(np.zeros(6))
    assert light_team.measure("dynamic_polytope").contains(np.zeros(6))


def test_accelerating_the_object_meets_its_equation_of_motion(arms_team):
    _, a, b = arms_team
    team = Team.holding([a, b], 5.0, task="spatial")
    an = analyze_team(team)
    a_o = np.array([0.4, -0.2, 0.3, 0.1, 0.0, -0.2])
    share = an.load_sharing(a_o)
    obj = team.held_object
    M_o = obj.inertia_matrix("spatial")
    W = an.terms.W
    h = share.wrenches.ravel()
    rhs = M_o @ a_o + obj.gravity_vector("spatial")
    np.testing.assert_allclose(W @ h, rhs, rtol=0, atol=1e-10 * np.abs(rhs).max())
    qdd = np.concatenate(share.accelerations)
    np.testing.assert_allclose(an.terms.J_u @ qdd, W.T @ a_o, rtol=0, atol=1e-9)
    tau = np.concatenate(share.torques)
    np.testing.assert_allclose(an.terms.P @ qdd, an.terms.xi + tau - an.terms.J_u.T @ h, atol=1e-8 * np.abs(tau).max())


# ----------------------------------------------------------------------------------------------
# robots that differ: TIAGo++ and the paper's robot, decoupled dynamics, a locked platform


@pytest.fixture(scope="module")
def mixed_team(robot, posture):
    tiago = mobmanip.load_robot("tiago_dual")
    q_t = tiago.hold_configuration()
    q_t[:4] = (0.4, 0.9, math.cos(-1.2), math.sin(-1.2))
    paper = paper_member(robot, posture, "paper", 0.1, -1.3, math.radians(70.0), angle_deg=10.0)
    return Team.holding([Member("tiago", tiago, q_t, (0, 1)), paper], 3.0, task="planar_rigid", decoupled=True)


def test_different_robots_kinematic_set_equals_the_lp(mixed_team, rng):
    an = analyze_team(mixed_team, measures=("kinematic_polytope",))
    lp = independent_kinematic_support(mixed_team.members, mixed_team.held_object.center)
    d = unit_directions(rng, 300, 3)
    np.testing.assert_allclose(an.measure("kinematic_polytope").supports(d), [lp(v) for v in d], rtol=1e-7)


def test_decoupled_team_dynamics_zero_each_robots_platform_arm_blocks(mixed_team):
    import scipy.linalg

    an = analyze_team(mixed_team)
    obj = mixed_team.held_object
    Js, Ps, xis, Ws = [], [], [], []
    for mem in mixed_team.members:
        J, P, xi, hands = pinocchio_blocks(mem, RIGID)
        P = P.copy()
        P[:2, 2:] = 0.0  # both platforms are differential drives: two wheel rates first
        P[2:, :2] = 0.0
        Js.append(J)
        Ps.append(P)
        xis.append(xi)
        Ws.extend(grasp_block_rigid(p - obj.center) for p in hands)
    tau_max = np.concatenate([m.robot.effort_limits for m in mixed_team.members])
    M_o = np.diag([obj.mass, obj.mass, obj.inertia[2, 2]])
    A, _, semi_axes = dynamic_ellipsoid_closed_form(
        scipy.linalg.block_diag(*Js),
        np.hstack(Ws),
        scipy.linalg.block_diag(*Ps),
        np.eye(len(tau_max)),
        np.concatenate(xis),
        M_o,
        np.zeros(3),
        tau_max,
    )
    got = an.measure("dynamic")
    np.testing.assert_allclose(got.semi_axes, semi_axes, rtol=1e-10)
    np.testing.assert_allclose(got.matrix, A, rtol=1e-9, atol=1e-12 * np.abs(A).max())


def test_a_locked_platform_takes_no_part(robot, posture, rng):
    """With one robot's platform fixed, its wheels leave the stacked terms, and the team's
    kinematic set can only shrink (the locked robot's own set is a subset of its mobile one)."""
    a = paper_member(robot, posture, "a", 0.0, -0.45, 0.0, angle_deg=20.0)
    b = paper_member(robot, posture, "b", 0.0, 0.45, 0.0, angle_deg=-20.0)
    locked = robot.with_platform("fixed")
    b_locked = Member("b", locked, b.q, (0, 1))
    mobile = analyze_team(Team.holding([a, b], 2.0, task="planar_rigid"), ("kinematic_polytope",))
    fixed = analyze_team(Team.holding([a, b_locked], 2.0, task="planar_rigid"), ("kinematic_polytope",))
    assert fixed.terms.J_u.shape[1] == mobile.terms.J_u.shape[1] - 2
    d = unit_directions(rng, 200, 3)
    lp = independent_kinematic_support([a, b_locked], fixed.team.held_object.center)
    got = fixed.measure("kinematic_polytope").supports(d)
    np.testing.assert_allclose(got, [lp(v) for v in d], rtol=1e-7)
    assert np.all(got <= mobile.measure("kinematic_polytope").supports(d) * (1 + 1e-9))


def test_ray_radius_is_the_nearest_facet_and_the_ellipsoid_quadratic(side_by_side, rng):
    _, an = side_by_side
    polytope = an.measure("kinematic_polytope")
    A, b = polytope.halfspaces  # facets from the hull enumeration; the ray uses one LP
    for u in unit_directions(rng, 100, 3):
        rate = A @ u
        hit = rate > 1e-12
        expected = np.min((b[hit] - A[hit] @ polytope.center) / rate[hit])
        assert ray_radius(polytope, u) == pytest.approx(expected, rel=1e-9)
        # the point reached lies on the boundary: inside, and a little further is outside
        r = ray_radius(polytope, u)
        assert polytope.contains(polytope.center + r * u) and not polytope.contains(polytope.center + 1.001 * r * u)
    ellipsoid = an.measure("kinematic")
    for u in unit_directions(rng, 20, 3):
        r = ray_radius(ellipsoid, 2.0 * u)
        assert (r * u) @ ellipsoid.matrix @ (r * u) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize(
    "inertia, words",
    [
        ("[1e308, 1.0, 1.0]", ["at most 1e+06 kg m^2", "1e+308"]),
        ("[1.0, -2.0, 1.0]", ["positive semi-definite"]),
        ("[1.0, 2.0]", ["3 principal moments or a 3 x 3 matrix"]),
    ],
)
def test_a_team_objects_inertia_out_of_range_is_one_error_naming_it(tmp_path, capfd, inertia, words):
    """The beam's inertia given in the team file instead of its size: 1e308 kg m^2 used to give "an
    object acceleration needs no joint torque" (its inverse rounds to zero); it is refused with
    the supported range, as are a negative moment and a wrong shape."""
    from hostile_util import assert_one_line_error, run_cli

    text = (Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml").read_text()
    text = text.replace("size = [1.5, 0.08, 0.08]", f"inertia = {inertia}")
    assert f"inertia = {inertia}" in text
    path = tmp_path / "team.toml"
    path.write_text(text)
    code, _, err = run_cli(capfd, "team", path)
    assert_one_line_error(code, err, *words)
