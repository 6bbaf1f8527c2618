"""The unified kinematic and dynamic ellipsoids (paper Eq. 23-38), checked against independent mathematics.

Reference sets, each computed here without the code under test:

* kinematic: the image of the unit ball of normalised joint velocities that a rigid object can
  follow (Monte-Carlo samples and the exact maximiser), and (J_hat^+ W^T)^T (J_hat^+ W^T);
* dynamic: {a_o : ||Z (Lambda_o a_o + mu_o)|| <= 1} with Lambda_o, mu_o rebuilt with numpy, the
  forward-dynamics image of the torque ball of the closed chain (robot + grasped object), and
  pycapacity's classical ellipsoids for one square arm;
* the fixed dual-arm system built from each arm's own Pinocchio Jacobian and mass-matrix block;
* small gravity-loaded arms written to tmp_path, with a point-mass load appended to the model
  (articulated-body forward dynamics) or a hand-computed static torque balance.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import scipy.linalg

import mobmanip
from mobmanip.analysis import analyze
from mobmanip.sets.ellipsoid import Ellipsoid
from mobmanip.terms.grasp import HeldObject

# ---------------------------------------------------------------------------------------------
# Constants from the paper (Tables 1 and 2) and the design notes.

WHEEL_RADIUS = 0.075  # m (Table 2)
ARM_SPEED = 3.14  # rad/s, every arm joint (Table 1)
ARM_TORQUE = (200.0, 100.0, 30.0)  # N m, joints 1-3 (Table 1)
LINK_LENGTHS = (0.5, 0.5, 0.5)  # m (Table 1)
RIGHT = ("arm_right_1_joint", "arm_right_2_joint", "arm_right_3_joint")
LEFT = ("arm_left_1_joint", "arm_left_2_joint", "arm_left_3_joint")
TOOLS = ("arm_right_tool_link", "arm_left_tool_link")
TASK_ROWS = {"planar": (0, 1), "planar_rigid": (0, 1, 5), "translational": (0, 1, 2), "spatial": (0, 1, 2, 3, 4, 5)}
G = 9.81  # m/s^2, Pinocchio's default gravity magnitude

# A generic (non-singular, non-symmetric) posture of both arms and a platform pose.
POSE = (0.3, 0.2, 0.4)
JOINTS = dict(zip(RIGHT + LEFT, (-0.5, 1.0, 0.7, 0.6, -1.2, -0.4)))

# Tolerances. The matrices below have entries O(1e-4 .. 1e2) and condition numbers below ~1e4;
# pseudo-inverses and SVDs then carry relative round-off ~1e-12. RTOL = 1e-9 leaves three orders of
# magnitude of margin and is still far below any physical effect tested.
RTOL = 1e-9
# Quadratic-form values of points that should lie exactly on a boundary (value 1): round-off only.
ON_BOUNDARY = 1e-9


def _rel(a, b):
    """Relative difference of two arrays in the Frobenius norm."""
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)) / np.linalg.norm(b))


def _quad(A, c, points):
    d = np.atleast_2d(points) - c
    return np.einsum("ij,jk,ik->i", d, A, d)


def _unit(rng, n, dim):
    v = rng.normal(size=(n, dim))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _same_ellipsoid(E, center, shape, rtol=RTOL):
    """E equals {center + G z} with G G^T = shape: compare E's G G^T and centre (basis-free)."""
    GGt = E.generator @ E.generator.T
    scale = np.linalg.norm(shape)
    assert np.linalg.norm(GGt - shape) <= rtol * scale, (GGt, shape)
    assert np.linalg.norm(E.center - center) <= rtol * max(np.linalg.norm(center), math.sqrt(scale))


# ---------------------------------------------------------------------------------------------
# Fixtures and independent models.


@pytest.fixture
def rng():
    return np.random.default_rng(20240611)


@pytest.fixture(scope="module")
def q0(paper):
    return paper.configuration(POSE, JOINTS)


def _write_spec(directory: Path, name: str, text: str) -> Path:
    path = directory / f"{name}.toml"
    path.write_text(text)
    return path


def _one_arm_spec(urdf: Path, platform: str) -> str:
    wheels = '[wheels]\nright = "wheel_right_joint"\nleft = "wheel_left_joint"\n' if platform != "fixed" else ""
    return (
        f'name = "one_arm_{platform}"\nurdf = "{urdf}"\nplatform = "{platform}"\ndefault_task = "planar_rigid"\n'
        f'{wheels}\n[[arms]]\nname = "right"\njoints = {json.dumps(list(RIGHT))}\nend_effector = "{TOOLS[0]}"\n'
    )


@pytest.fixture(scope="module")
def one_arm(paper, tmp_path_factory):
    """The paper robot's right arm alone: on a locked platform (square in planar_rigid) and mobile."""
    tmp = tmp_path_factory.mktemp("one_arm")
    urdf = paper.spec.urdf.resolve()
    return {
        kind: mobmanip.load_robot(_write_spec(tmp, f"one_arm_{kind}", _one_arm_spec(urdf, kind)))
        for kind in ("fixed", "differential_drive")
    }


class OwnModel:
    """The paper URDF loaded directly with Pinocchio (planar root joint), indexed by joint name."""

    def __init__(self, urdf):
        self.model = pin.buildModelFromUrdf(str(urdf), pin.JointModelPlanar())
        self.data = self.model.createData()

    def q(self, pose, joints):
        q = pin.neutral(self.model)
        x, y, yaw = pose
        q[:4] = (x, y, math.cos(yaw), math.sin(yaw))
        for name, value in joints.items():
            q[self.model.joints[self.model.getJointId(name)].idx_q] = value
        return q

    def v_index(self, names):
        return [self.model.joints[self.model.getJointId(n)].idx_v for n in names]

    def arm_jacobian(self, q, tool, joints, rows):
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        J = pin.getFrameJacobian(self.model, self.data, self.model.getFrameId(tool), pin.LOCAL_WORLD_ALIGNED)
        return J[np.ix_(list(rows), self.v_index(joints))]

    def tool_position(self, q, tool):
        pin.framesForwardKinematics(self.model, self.data, q)
        return self.data.oMf[self.model.getFrameId(tool)].translation.copy()

    def mass_block(self, q, joints):
        M = pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T  # older Pinocchio fills only the upper triangle
        idx = self.v_index(joints)
        return M[np.ix_(idx, idx)]


@pytest.fixture(scope="module")
def own(paper):
    return OwnModel(paper.spec.urdf)


def _paper_maps(an, P=None):
    """Lambda_o and mu_o of Eq. 33-35 (with the sign of Eq. 28) rebuilt with numpy from an analysis."""
    J, W, Q, xi = an.unified_jacobian, an.grasp_matrix, an.input_matrix, an.bias
    if P is None:
        P = an.reduced_inertia_decoupled if an.decoupled else an.reduced_inertia
    M_o = an.held_object.inertia_matrix(an.task)
    g_o = an.held_object.gravity_vector(an.task)
    J_pinv, W_pinv, Q_inv = np.linalg.pinv(J), np.linalg.pinv(W), np.linalg.inv(Q)
    Lam = Q_inv @ P @ J_pinv @ W.T + Q_inv @ J.T @ W_pinv @ M_o
    mu = -Q_inv @ xi + Q_inv @ J.T @ W_pinv @ g_o
    return Lam, mu


def _closed_chain_forward_dynamics(an, P=None):
    """Object acceleration as an affine map of the torques, a_o = F tau + f0, for robot and object at rest.

    Unknowns (qdd, a_o, h): P qdd + J^T h = Q tau + xi (robot, Eq. 16 with the grasp wrenches h),
    M_o a_o - W h = -g_o (object, Eq. 17 and 22), J qdd - W^T a_o = 0 (rigid grasp, Eq. 20-21 at
    rest). Internal forces are whatever the equations make them, not W^+'s minimum-norm choice.
    """
    J, W, Q, xi = an.unified_jacobian, an.grasp_matrix, an.input_matrix, an.bias
    if P is None:
        P = an.reduced_inertia
    M_o = an.held_object.inertia_matrix(an.task)
    g_o = an.held_object.gravity_vector(an.task)
    nx, mk, m = J.shape[1], J.shape[0], W.shape[0]
    K = np.block(
        [
            [P, np.zeros((nx, m)), J.T],
            [np.zeros((m, nx)), M_o, -W],
            [J, -W.T, np.zeros((mk, mk))],
        ]
    )
    rhs_tau = np.vstack([Q, np.zeros((m + mk, nx))])
    rhs_0 = np.concatenate([xi, -g_o, np.zeros(mk)])
    F = np.linalg.solve(K, rhs_tau)[nx : nx + m]
    f0 = np.linalg.solve(K, rhs_0)[nx : nx + m]
    return F, f0


def _consistent_motions(J_hat, W):
    """Normalised joint motions a rigid object can follow, and the object velocity they give.

    The first arm's velocity fixes the object's: v_o = W_1^-T v_1; every other arm must then move
    with v_i = W_i^T v_o. Returns an orthonormal basis N of those motions (scipy null_space) and
    the map T with v_o = T qbar.
    """
    m = W.shape[0]
    k = W.shape[1] // m
    T = np.linalg.solve(W[:, :m].T, J_hat[:m])
    if k == 1:
        return np.eye(J_hat.shape[1]), T
    constraints = np.vstack([W[:, m * i : m * (i + 1)].T @ T - J_hat[m * i : m * (i + 1)] for i in range(1, k)])
    return scipy.linalg.null_space(constraints), T


# =============================================================================================
# Ellipsoid helpers on synthetic ellipsoids.


def _random_ellipsoid(rng, m, d=None):
    center = rng.normal(size=m)
    Gm = rng.normal(size=(m, d or m))
    return Ellipsoid.from_generator(center, Gm), center, Gm


@pytest.mark.parametrize("m", [2, 3, 6])
def test_from_generator_semi_axes_axes_and_matrix(m, rng):
    for d in (m, m + 2):
        E, c, Gm = _random_ellipsoid(rng, m, d)
        shape = Gm @ Gm.T
        eig = np.sort(np.linalg.eigvalsh(shape))[::-1]
        np.testing.assert_allclose(E.semi_axes, np.sqrt(eig), rtol=1e-12)
        assert np.all(np.diff(E.semi_axes) <= 0)
        np.testing.assert_allclose(E.axes @ E.axes.T, np.eye(m), rtol=0, atol=1e-12)
        np.testing.assert_allclose(E.matrix, np.linalg.inv(shape), rtol=1e-9)
        for s, a in zip(E.semi_axes, E.axes):
            np.testing.assert_allclose(shape @ a, s**2 * a, rtol=0, atol=1e-10 * eig[0])
        _same_ellipsoid(E, c, shape)
        assert not E.degenerate and not E.empty


def test_contains_matches_the_quadratic_form(rng):
    E, c, Gm = _random_ellipsoid(rng, 3)
    A = np.linalg.inv(Gm @ Gm.T)
    points = c + rng.uniform(-1.5, 1.5, size=(4000, 3)) @ Gm.T  # a box in the generator's own coordinates
    value = _quad(A, c, points)
    clear = np.abs(value - 1.0) > 1e-6  # leave out a thin shell where round-off decides
    np.testing.assert_array_equal(E.contains(points)[clear], (value <= 1.0)[clear])
    assert 500 < np.sum(value[clear] <= 1.0) < 3500  # both outcomes are exercised


def test_support_radius_and_boundary_of_an_ellipse(rng):
    E, c, Gm = _random_ellipsoid(rng, 2)
    boundary = E.boundary(20001)
    A = np.linalg.inv(Gm @ Gm.T)
    np.testing.assert_allclose(_quad(A, c, boundary), 1.0, rtol=0, atol=ON_BOUNDARY)
    for d in _unit(rng, 50, 2):
        exact = d @ c + math.sqrt(d @ Gm @ Gm.T @ d)
        assert E.support(d) == pytest.approx(exact, rel=1e-12)
        assert E.support(3.0 * d) == pytest.approx(3.0 * exact, rel=1e-12)
        # Dense boundary sampling: spacing 2 pi / 20000 rad gives a cosine error ~5e-8 of the radius.
        sampled = np.max(boundary @ d)
        assert sampled <= E.support(d) + 1e-12
        assert sampled >= E.support(d) - 1e-7 * E.semi_axes[0]
        assert E.radius_along(5.0 * d) == pytest.approx(math.sqrt(d @ Gm @ Gm.T @ d), rel=1e-12)
    with pytest.raises(ValueError):
        _random_ellipsoid(rng, 3)[0].boundary()


def _rotation(rng, m):
    """A random rotation (orthogonal, det +1) from the QR factorisation of a Gaussian matrix."""
    Qm, R = np.linalg.qr(rng.normal(size=(m, m)))
    Qm = Qm * np.sign(np.diag(R))
    if np.linalg.det(Qm) < 0:
        Qm[:, 0] *= -1
    return Qm


def test_volume_isotropy_and_manipulability(rng):
    E2 = Ellipsoid.from_generator(np.zeros(2), np.diag([3.0, 0.5]) @ _rotation(rng, 2))
    assert E2.volume == pytest.approx(math.pi * 3.0 * 0.5, rel=1e-12)
    assert E2.isotropy == pytest.approx(0.5 / 3.0, rel=1e-12)
    assert E2.manipulability == pytest.approx(1.5, rel=1e-12)
    E3 = Ellipsoid.from_generator(np.ones(3), _rotation(rng, 3) @ np.diag([2.0, 0.25, 1.0]))
    assert E3.volume == pytest.approx(4.0 / 3.0 * math.pi * 2.0 * 0.25 * 1.0, rel=1e-12)
    assert E3.isotropy == pytest.approx(0.125, rel=1e-12)
    # Volume equals the Monte-Carlo fraction of a box: 200k samples -> ~0.5 % standard error.
    box = rng.uniform(-1.0, 1.0, size=(200_000, 3)) * E3.semi_axes[0] + E3.center
    fraction = np.mean(E3.contains(box))
    assert fraction * (2 * E3.semi_axes[0]) ** 3 == pytest.approx(E3.volume, rel=0.02)


@pytest.mark.parametrize("dims", [(0, 1), (0, 2), (2, 1)])
def test_projection_and_slice_of_a_3d_ellipsoid(dims, rng):
    E, c, Gm = _random_ellipsoid(rng, 3)
    idx = list(dims)
    # Shadow: {c_I + G_I z}; its shape matrix is G_I G_I^T.
    _same_ellipsoid(E.project(dims), c[idx], Gm[idx] @ Gm[idx].T)
    # Slice through the centre (other coordinates at the centre): y^T A_II y <= 1.
    A = np.linalg.inv(Gm @ Gm.T)
    _same_ellipsoid(E.slice(dims), c[idx], np.linalg.inv(A[np.ix_(idx, idx)]))
    # The slice lies inside the shadow.
    S, P = E.slice(dims), E.project(dims)
    for d in _unit(rng, 30, 2):
        assert S.support(d) <= P.support(d) + 1e-12


def test_degenerate_generator(rng):
    """A rank-deficient generator: a zero semi-axis, the flag, a pseudo-inverse matrix, a flat contains()."""
    u = np.array([1.0, 2.0, -1.0]) / math.sqrt(6.0)
    Gm = rng.normal(size=(3, 3))
    Gm -= np.outer(u, u @ Gm)  # range(G) is orthogonal to u
    c = rng.normal(size=3)
    E = Ellipsoid.from_generator(c, Gm)
    assert E.degenerate and not E.empty
    assert E.semi_axes[-1] == 0.0 and E.semi_axes[1] > 0.1
    assert abs(E.axes[-1] @ u) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(E.matrix, np.linalg.pinv(Gm @ Gm.T), rtol=0, atol=1e-9 * np.abs(E.matrix).max())
    assert np.isfinite(E.to_dict()["volume"]) and E.volume == 0.0 and E.isotropy == 0.0
    inside = c + 0.9 * _unit(rng, 100, 3) @ Gm.T
    assert E.contains(inside).all()
    assert not E.contains(inside + 1e-6 * u).any()

    # Flat along z: a flat ellipse in the x-y plane, generator G2 (2 x 2).
    G2 = rng.normal(size=(2, 2))
    flat = Ellipsoid.from_generator(c, np.vstack([G2, np.zeros((1, 2))]))
    A2 = np.linalg.inv(G2 @ G2.T)
    assert flat.degenerate and flat.semi_axes[2] == 0.0
    # Shadow on x-y: the full ellipse. Shadow on x-z: the segment |x| <= |G2[0]| (no extent in z).
    _same_ellipsoid(flat.project((0, 1)), c[:2], G2 @ G2.T)
    _same_ellipsoid(flat.project((0, 2)), c[[0, 2]], np.diag([G2[0] @ G2[0], 0.0]))
    # Slice in x-z through the centre (y at the centre): z = 0 and x^2 A2[0, 0] <= 1, a segment.
    _same_ellipsoid(flat.slice((0, 2)), c[[0, 2]], np.diag([1.0 / A2[0, 0], 0.0]))
    assert flat.slice((0, 2)).degenerate and not flat.slice((0, 1)).degenerate
    _same_ellipsoid(flat.slice((0, 1)), c[:2], G2 @ G2.T)


def test_to_dict_is_strict_json(rng):
    E = _random_ellipsoid(rng, 3)[0]
    data = json.loads(json.dumps(E.to_dict(), allow_nan=False))
    np.testing.assert_allclose(data["matrix"], E.matrix, rtol=0, atol=0)
    assert data["volume"] == E.volume


# =============================================================================================
# Kinematic ellipsoid.


@pytest.mark.parametrize("locked", [False, True], ids=["mobile", "locked"])
@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_kinematic_ellipsoid_is_the_image_of_the_unit_ball(paper, q0, task, locked, rng):
    robot = paper.with_platform("fixed") if locked else paper
    an = analyze(robot, q0, task)
    E = an.kinematic
    A = E.matrix
    W = an.grasp_matrix
    J_hat = an.unified_jacobian * robot.velocity_limits
    N, T = _consistent_motions(J_hat, W)
    K = T @ N  # object velocity per coordinate of the consistent unit ball
    assert E.center.tolist() == [0.0] * W.shape[0]

    # 1. Uniform samples of the unit sphere of consistent motions land inside.
    z = _unit(rng, 5000, N.shape[1])
    qbar = z @ N.T
    v = qbar @ T.T
    # they really are rigid-object motions: every arm moves with W_i^T v_o
    np.testing.assert_allclose(qbar @ J_hat.T, v @ W, rtol=0, atol=1e-10)
    assert np.all(_quad(A, 0.0, v) <= 1.0 + ON_BOUNDARY)

    # 2. The minimum-norm motion towards any direction, scaled to unit norm, lands on the boundary.
    for u in _unit(rng, 50, W.shape[0]):
        qbar_u = np.linalg.lstsq(J_hat, W.T @ u, rcond=None)[0]
        np.testing.assert_allclose(J_hat @ qbar_u, W.T @ u, rtol=0, atol=1e-12)
        point = u / np.linalg.norm(qbar_u)
        assert _quad(A, 0.0, point)[0] == pytest.approx(1.0, abs=ON_BOUNDARY)
        assert E.contains(point) and not E.contains(point * (1 + 1e-6))

    # 3. Support in each direction: no sample exceeds it; the exact maximiser K^T d / |K^T d| reaches it,
    # and samples in its neighbourhood (perturbation 1e-3) come within the second-order gap
    # ~ |K| (1e-3)^2 d_z, bounded by 1e-5 relative.
    for d in _unit(rng, 40, W.shape[0]):
        support = E.support(d)
        assert np.max(v @ d) <= support * (1 + 1e-12)
        z_star = K.T @ d / np.linalg.norm(K.T @ d)
        assert d @ K @ z_star == pytest.approx(support, rel=1e-10)
        near = z_star + 1e-3 * rng.normal(size=(200, N.shape[1]))
        near /= np.linalg.norm(near, axis=1, keepdims=True)
        values = near @ K.T @ d
        assert values.max() <= support * (1 + 1e-12)
        assert values.max() >= support * (1 - 1e-5)


@pytest.mark.parametrize("locked", [False, True], ids=["mobile", "locked"])
@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_kinematic_matrix_is_the_paper_form_when_J_hat_has_full_row_rank(paper, task, locked, rng):
    """A = (J_hat^+ W^T)^T (J_hat^+ W^T), the consistent form of Eq. 26 (DESIGN.md erratum)."""
    robot = paper.with_platform("fixed") if locked else paper
    checked = 0
    while checked < 5:
        joints = {name: float(rng.uniform(-math.pi, math.pi)) for name in RIGHT + LEFT}
        q = robot.configuration(tuple(rng.uniform(-2, 2, size=3)), joints)
        an = analyze(robot, q, task)
        J_hat = an.unified_jacobian * robot.velocity_limits
        sv = np.linalg.svd(J_hat, compute_uv=False)
        if sv[-1] < 1e-2 * sv[0]:  # keep well-conditioned draws (full row rank with margin)
            continue
        checked += 1
        B = np.linalg.pinv(J_hat) @ an.grasp_matrix.T
        assert _rel(an.kinematic.matrix, B.T @ B) < RTOL


@pytest.mark.parametrize("task", ["translational", "spatial"])
def test_ellipsoids_of_tasks_the_planar_robot_only_partly_spans(paper, q0, task, rng):
    """Vertical joint axes: the tools cannot move in z (nor roll or pitch). J_hat loses row rank, the
    kinematic set is the image of the consistent unit ball (flat along z), and the dynamic set is the
    defining inequality restricted to accelerations with W^T a_o in range(J)."""
    an = analyze(paper, q0, task)
    W = an.grasp_matrix
    m = W.shape[0]
    J_hat = an.unified_jacobian * paper.velocity_limits
    N, T = _consistent_motions(J_hat, W)
    K = T @ N
    _same_ellipsoid(an.kinematic, np.zeros(m), K @ K.T)
    flat = np.zeros(m)
    flat[2] = 1.0  # z
    for E in (an.kinematic, an.dynamic):
        assert E.degenerate and not E.empty
        assert E.radius_along(flat) < 1e-12 * E.semi_axes[0]
        assert not E.contains(E.center + 1e-6 * flat)
    v = _unit(rng, 2000, N.shape[1]) @ K.T
    assert an.kinematic.contains(v, tol=1e-9).all()

    # Dynamic: feasible accelerations F = {a : W^T a in range(J)} (scipy null_space of the part of
    # W^T outside range(J)), and the set ||L b + mu_bar|| <= 1 for a = F b.
    J = an.unified_jacobian
    range_J = scipy.linalg.orth(J)
    F = scipy.linalg.null_space(W.T - range_J @ (range_J.T @ W.T))
    assert F.shape[1] == {"translational": 2, "spatial": 3}[task]  # x, y (and yaw) of the object
    Lam, mu = _paper_maps(an)
    Z = 1.0 / paper.effort_limits
    L = Z[:, None] * Lam @ F
    b_c = -np.linalg.lstsq(L, Z * mu, rcond=None)[0]
    r = Z * mu + L @ b_c
    shape = F @ np.linalg.inv(L.T @ L / (1.0 - r @ r)) @ F.T
    _same_ellipsoid(an.dynamic, F @ b_c, shape)


def test_square_single_arm_matches_pycapacity(one_arm, own):
    """One 3R arm, platform locked, task planar_rigid (m = 3 = n): classical ellipsoids."""
    pytest.importorskip("pycapacity")
    from pycapacity.robot import acceleration_ellipsoid, velocity_ellipsoid

    robot = one_arm["fixed"]
    joints = {"arm_right_1_joint": 0.4, "arm_right_2_joint": -1.1, "arm_right_3_joint": 0.9}
    q = robot.configuration((0.0, 0.0, 0.0), joints)
    an = analyze(robot, q, "planar_rigid")
    q_own = own.q((0.0, 0.0, 0.0), joints)
    J = own.arm_jacobian(q_own, TOOLS[0], RIGHT, TASK_ROWS["planar_rigid"])
    M = own.mass_block(q_own, RIGHT)
    np.testing.assert_array_equal(an.grasp_matrix, np.eye(3))  # one arm: the end effector is the task point
    for E, ref in (
        (an.kinematic, velocity_ellipsoid(J, [ARM_SPEED] * 3)),
        (an.dynamic, acceleration_ellipsoid(J, M, list(ARM_TORQUE))),
    ):
        radii = np.sort(np.asarray(ref.radii))[::-1]
        np.testing.assert_allclose(E.semi_axes, radii, rtol=RTOL)
        order = np.argsort(np.asarray(ref.radii))[::-1]
        rotation = np.asarray(ref.rotation)[:, order]
        for a, r in zip(E.axes, rotation.T):  # same directions up to sign (distinct semi-axes)
            assert abs(a @ r) == pytest.approx(1.0, abs=1e-9)
        np.testing.assert_allclose(E.center, 0.0, atol=1e-12)


def _fixed_dual_arm(own, pose, joints, task, obj: HeldObject):
    """The fixed dual-arm system from the arms' own Jacobians and mass-matrix block (no platform)."""
    rows = TASK_ROWS[task]
    q = own.q(pose, joints)
    J1 = own.arm_jacobian(q, TOOLS[0], RIGHT, rows)
    J2 = own.arm_jacobian(q, TOOLS[1], LEFT, rows)
    J = scipy.linalg.block_diag(J1, J2)
    M = own.mass_block(q, RIGHT + LEFT)
    m = len(rows)
    # W from the grasp offsets written out here: forces pass through, moment rows add r x f (z only).
    blocks = []
    for r in obj.offsets:
        Wi = np.eye(m)
        if task == "planar_rigid":
            Wi[2, :2] = (-r[1], r[0])
        blocks.append(Wi)
    W = np.hstack(blocks)
    M_o = obj.mass * np.eye(m)
    if task == "planar_rigid":
        M_o[2, 2] = obj.inertia[2, 2]
    J_hat = J * ARM_SPEED
    B = np.linalg.pinv(J_hat) @ W.T
    A_kin = B.T @ B
    Z = 1.0 / np.array(ARM_TORQUE * 2)
    Lam = M @ np.linalg.pinv(J) @ W.T + J.T @ np.linalg.pinv(W) @ M_o
    L = Z[:, None] * Lam
    A_dyn = L.T @ L
    return A_kin, A_dyn


@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_locked_platform_equals_the_fixed_dual_arm_system(paper, own, task):
    locked = paper.with_platform("fixed")
    q = locked.configuration(POSE, JOINTS)
    probe = analyze(locked, q, task)
    obj = HeldObject(2.0, np.diag([0.0, 0.0, 0.05]), probe.held_object.center, probe.held_object.offsets)
    an = analyze(locked, q, task, held_object=obj)
    A_kin, A_dyn = _fixed_dual_arm(own, POSE, JOINTS, task, obj)
    assert _rel(an.kinematic.matrix, A_kin) < RTOL
    assert _rel(an.dynamic.matrix, A_dyn) < RTOL
    np.testing.assert_allclose(an.dynamic.center, 0.0, atol=1e-12)  # vertical joint axes: no gravity load


def test_kinematic_converges_to_the_fixed_system_as_the_wheels_slow_down(paper, own, q0):
    """Rim speed 1e-1 ... 1e-6 m/s: the wheel columns of J_hat shrink linearly, so the matrix error
    shrinks quadratically; we require a tenfold decrease per decade and 1e-9 relative at 1e-6 m/s."""
    A_fixed, _ = _fixed_dual_arm(own, POSE, JOINTS, "planar", HeldObject.between(np.zeros((2, 3)), 2.0))
    errors = []
    for speed in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6):
        an = analyze(paper.with_wheel_limits(velocity=speed / WHEEL_RADIUS), q0, "planar")
        errors.append(_rel(an.kinematic.matrix, A_fixed))
    assert errors[0] > 1e-3  # the platform does matter at 0.1 m/s
    assert all(b < 0.1 * a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-9


def test_kinematic_ellipsoids_grow_with_wheel_speed(paper, q0):
    """Larger limits scale the wheel columns of J_hat up: every reachable set contains the previous one
    (A_slow - A_fast is positive semi-definite), and the locked platform is inside all of them."""
    previous = analyze(paper.with_platform("fixed"), q0, "planar").kinematic.matrix
    for speed in (0.001, 0.5, 1.0, 3.0):
        A = analyze(paper.with_wheel_limits(velocity=speed / WHEEL_RADIUS), q0, "planar").kinematic.matrix
        assert np.linalg.eigvalsh(previous - A).min() >= -1e-12 * np.abs(previous).max()
        previous = A


# =============================================================================================
# Dynamic ellipsoid.

DYNAMIC_CASES = [
    ("mobile", "planar", False),
    ("mobile", "planar", True),
    ("mobile", "planar_rigid", False),
    ("locked", "planar", False),
    ("locked", "planar_rigid", False),
]


@pytest.mark.parametrize(("platform", "task", "decoupled"), DYNAMIC_CASES)
def test_dynamic_ellipsoid_is_its_defining_set(paper, q0, platform, task, decoupled, rng):
    """contains() agrees with ||Z (Lambda_o a + mu_o)|| <= 1; boundary points have norm 1; torque samples
    of the unit sphere in the reachable affine set land on the boundary."""
    robot = paper.with_platform("fixed") if platform == "locked" else paper
    an = analyze(robot, q0, task, decoupled=decoupled)
    E = an.dynamic
    Lam, mu = _paper_maps(an)
    Z = 1.0 / robot.effort_limits
    L, mu_bar = Z[:, None] * Lam, Z * mu
    m = E.dim
    assert not E.degenerate and not E.empty

    def norm(points):
        return np.linalg.norm(np.atleast_2d(points) @ L.T + mu_bar, axis=1)

    # Random points around the ellipsoid, classified by the defining inequality. The box is drawn in the
    # coordinates y = L (a - a_c) of the independent maps (a_c = -L^+ mu_bar), so it hugs the set.
    a_c = -np.linalg.lstsq(L, mu_bar, rcond=None)[0]
    box = rng.uniform(-1.3, 1.3, size=(5000, m)) @ (np.linalg.pinv(L) @ scipy.linalg.orth(L)).T
    points = a_c + box
    value = norm(points)
    clear = np.abs(value - 1.0) > 1e-6
    np.testing.assert_array_equal(E.contains(points)[clear], (value <= 1.0)[clear])
    assert 500 < np.sum(value[clear] <= 1.0) < 4500  # both outcomes exercised

    # Boundary points c + G z, |z| = 1.
    boundary = E.center + _unit(rng, 500, m) @ E.generator.T
    np.testing.assert_allclose(norm(boundary), 1.0, rtol=0, atol=ON_BOUNDARY)

    # Torque side: the normalised torques Z (Lambda a + mu) reachable at rest form the affine set
    # mu_bar + range(L); its points of unit norm are r + sqrt(1 - |r|^2) u with r the part of mu_bar
    # outside range(L) and u a unit vector of range(L). Each maps back to a boundary acceleration.
    basis = scipy.linalg.orth(L)
    r = mu_bar - basis @ (basis.T @ mu_bar)
    for u in _unit(rng, 200, basis.shape[1]) @ basis.T:
        tau_bar = r + math.sqrt(1.0 - r @ r) * u
        a = np.linalg.lstsq(L, tau_bar - mu_bar, rcond=None)[0]
        np.testing.assert_allclose(L @ a + mu_bar, tau_bar, rtol=0, atol=1e-10)
        assert E.contains(a)
        assert _quad(E.matrix, E.center, a)[0] == pytest.approx(1.0, abs=ON_BOUNDARY)

    # Matrix and centre from the independent maps: A = L^T L / (1 - |r|^2), c = -L^+ mu_bar.
    assert _rel(E.matrix, L.T @ L / (1.0 - r @ r)) < RTOL
    np.testing.assert_allclose(E.center, -np.linalg.pinv(L) @ mu_bar, rtol=0, atol=1e-9)


@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_paper_dynamic_ellipsoid_lies_inside_the_forward_dynamics_image(paper, q0, task, rng):
    """Redundant mobile dual arm holding a 2 kg object (coupled dynamics).

    For any a_o of the paper's set, the torque tau = Lambda_o a_o + mu_o, fed to the closed-chain
    forward dynamics, produces exactly a_o (the paper's motion q_dd = J^+ W^T a_o, h = W^+ (M_o a_o + g_o)
    satisfies every equation). So the paper's ellipsoid is inside the forward-dynamics image of
    the torque ball; the image is strictly larger (other joint-acceleration splits, internal forces).
    """
    an = analyze(paper, q0, task)
    E = an.dynamic
    Lam, mu = _paper_maps(an)
    F, f0 = _closed_chain_forward_dynamics(an)
    Z = 1.0 / paper.effort_limits
    image = Ellipsoid.from_generator(f0, F / Z)  # {F tau + f0 : |Z tau| <= 1}
    for a in E.center + _unit(rng, 100, E.dim) @ E.generator.T:
        tau = Lam @ a + mu
        assert np.linalg.norm(Z * tau) == pytest.approx(1.0, abs=ON_BOUNDARY)
        np.testing.assert_allclose(F @ tau + f0, a, rtol=1e-9, atol=1e-9)
    ratios = []
    for d in _unit(rng, 300, E.dim):
        assert E.support(d) <= image.support(d) * (1 + 1e-10) + 1e-12
        ratios.append(image.support(d) / E.support(d))
    assert max(ratios) > 1.05  # genuinely redundant: the physical set is larger somewhere


def test_single_arm_forward_dynamics_contains_the_paper_set_and_equals_it_when_square(one_arm, rng):
    """One arm, no object (W = I, M_o = 0): forward dynamics a = J P^-1 tau.

    Mobile (5 wheel/joint rates for 3 task coordinates: redundant): paper set inside the image,
    strictly somewhere. Locked platform (3 x 3 J): the two sets coincide.
    """
    joints = {"arm_right_1_joint": 0.4, "arm_right_2_joint": -1.1, "arm_right_3_joint": 0.9}
    for kind, square in (("differential_drive", False), ("fixed", True)):
        robot = one_arm[kind]
        an = analyze(robot, robot.configuration((0.5, -0.3, 1.0), joints), "planar_rigid")
        assert an.held_object.mass == 0.0
        J, P = an.unified_jacobian, an.reduced_inertia
        Z = 1.0 / robot.effort_limits
        image_G = J @ np.linalg.solve(P, np.diag(1.0 / Z))  # {J P^-1 tau : |Z tau| <= 1}
        image = Ellipsoid.from_generator(np.zeros(3), image_G)
        ratios = []
        for d in _unit(rng, 300, 3):
            assert an.dynamic.support(d) <= image.support(d) * (1 + 1e-10)
            ratios.append(image.support(d) / an.dynamic.support(d))
        if square:
            assert _rel(an.dynamic.matrix, image.matrix) < RTOL
        else:
            assert max(ratios) > 1.05
        # Forward dynamics of torque samples inside the ball. Square case: the paper assigns each
        # resulting acceleration exactly the sample's torque, so all lie inside. Redundant case:
        # q_dd = J^+ a is the minimum-norm joint acceleration, not the minimum-torque one, so the
        # paper's torque can exceed the sample's and some achievable accelerations lie outside.
        taus = _unit(rng, 300, robot.nx) * rng.uniform(0, 1, size=(300, 1)) / Z
        accel = taus @ np.linalg.solve(P, np.eye(robot.nx)).T @ J.T
        Lam, mu = _paper_maps(an)
        paper_norm = np.linalg.norm((accel @ Lam.T + mu) * Z, axis=1)
        sample_norm = np.linalg.norm(taus * Z, axis=1)
        if square:
            np.testing.assert_allclose(paper_norm, sample_norm, rtol=1e-9)
            assert an.dynamic.contains(accel, tol=1e-9).all()
        else:
            assert np.any(paper_norm > sample_norm * (1 + 1e-6))
            clear = np.abs(paper_norm - 1.0) > 1e-6
            np.testing.assert_array_equal(an.dynamic.contains(accel)[clear], (paper_norm <= 1.0)[clear])
            assert not an.dynamic.contains(accel).all()


def test_dynamic_limits_of_the_platform(paper, own, q0, tmp_path):
    """Which limit makes the mobile dynamic ellipsoid the fixed one?

    In the paper's model the joint accelerations are q_dd = J^+ W^T a_o, the *unweighted*
    minimum-norm split between wheels and arms: it depends on J only, not on any limit. A huge
    wheel torque therefore only removes the wheel rows from ||Z tau||; the arms still pay for the
    J^+ split and for the platform-arm coupling, and the limit A_inf = (Z_a Lambda_a)^T (Z_a Lambda_a)
    (arm rows only) is *not* the fixed dual-arm ellipsoid. The platform "hardly moves" in that
    model when the wheels' columns of J vanish: with a wheel radius r -> 0 (same wheel limits), J_w
    and the platform-arm blocks of P are O(r), J^+ -> [0; J_a^+] and the wheel torques -> 0, so the
    ellipsoid converges to the fixed one, coupled or decoupled, with an O(r^2) matrix error.
    """
    # 1. Huge wheel torque: convergence to the arm-rows-only limit, which differs from the fixed one.
    an = analyze(paper, q0, "planar")
    Lam, _ = _paper_maps(an)
    Z = 1.0 / paper.effort_limits
    arm = slice(2, None)
    L_arm = Z[arm, None] * Lam[arm]
    A_inf = L_arm.T @ L_arm
    errors = [
        _rel(analyze(paper.with_wheel_limits(effort=t), q0, "planar").dynamic.matrix, A_inf)
        for t in (1e2, 1e3, 1e4, 1e5, 1e6, 1e7)
    ]
    assert all(b < 0.1 * a for a, b in zip(errors, errors[1:])), errors  # O(1 / tau^2)
    assert errors[-1] < 1e-9
    obj = HeldObject.between(np.zeros((2, 3)), 2.0)
    _, A_fixed = _fixed_dual_arm(own, POSE, JOINTS, "planar", obj)
    assert _rel(A_inf, A_fixed) > 1e-3

    # 2. Vanishing wheel radius (spec override of the URDF geometry): convergence to the fixed system.
    spec = paper.spec.source.read_text().replace('urdf = "planar_dual_arm.urdf"', f'urdf = "{paper.spec.urdf}"')
    assert "# radius = 0.075" in spec
    for decoupled in (False, True):
        errors = []
        for radius in (1e-1, 1e-2, 1e-3, 1e-4, 1e-6):
            path = _write_spec(tmp_path, f"r{radius:g}", spec.replace("# radius = 0.075", f"radius = {radius!r}"))
            small = mobmanip.load_robot(path)
            errors.append(_rel(analyze(small, q0, "planar", decoupled=decoupled).dynamic.matrix, A_fixed))
        assert errors[0] > 1e-2
        assert all(b < 0.1 * a for a, b in zip(errors, errors[1:])), errors
        assert errors[-1] < 1e-8


def _synthetic_problem(rng, m=3, k=2, nx=9):
    """Random well-posed arrays for the ellipsoid functions: full-row-rank J, SPD P, an invertible
    non-identity Q, a bias xi and an object gravity g_o that shift the centre."""
    J = rng.normal(size=(m * k, nx))
    offsets = rng.uniform(-0.3, 0.3, size=(k, 3))
    W = np.hstack([np.eye(m) for _ in range(k)])
    W[2, 0::m] = -offsets[:, 1]  # planar_rigid blocks: yaw moment row r x f
    W[2, 1::m] = offsets[:, 0]
    B = rng.normal(size=(nx, nx))
    P = B @ B.T + nx * np.eye(nx)
    Q = np.eye(nx) + 0.3 * rng.normal(size=(nx, nx))
    xi = rng.normal(size=nx)
    M_o = np.diag([2.0, 2.0, 0.05])
    g_o = rng.normal(size=m)
    return J, W, P, Q, xi, M_o, g_o


def test_dynamic_ellipsoid_function_with_a_general_input_matrix(rng):
    """dynamic_ellipsoid on arrays, Q not the identity: A = L^T L / (1 - |r|^2), c = -L^+ mu_bar with
    L = Z Q^-1 (P J^+ W^T + J^T W^+ M_o), mu_bar = Z Q^-1 (-xi + J^T W^+ g_o); empty exactly when the
    effort limits are scaled below |r| (r scales as 1 / limit)."""
    from mobmanip.sets.ellipsoid import dynamic_ellipsoid

    J, W, P, Q, xi, M_o, g_o = _synthetic_problem(rng)
    effort = rng.uniform(20.0, 100.0, size=J.shape[1])
    Q_inv = np.linalg.inv(Q)
    Lam = Q_inv @ (P @ np.linalg.pinv(J) @ W.T + J.T @ np.linalg.pinv(W) @ M_o)
    mu = Q_inv @ (-xi + J.T @ np.linalg.pinv(W) @ g_o)

    def reference(scale):
        Z = 1.0 / (scale * effort)
        L, mu_bar = Z[:, None] * Lam, Z * mu
        centre = -np.linalg.pinv(L) @ mu_bar
        r = mu_bar + L @ centre
        return L, centre, r

    L, centre, r = reference(1.0)
    assert 1e-6 < r @ r < 1.0
    E = dynamic_ellipsoid(J, W, P, Q, xi, M_o, g_o, effort)
    assert _rel(E.matrix, L.T @ L / (1.0 - r @ r)) < RTOL
    np.testing.assert_allclose(E.center, centre, rtol=1e-9, atol=1e-12)
    threshold = float(np.linalg.norm(r))
    for scale, empty in ((threshold * (1 + 1e-6), False), (threshold * (1 - 1e-6), True)):
        E = dynamic_ellipsoid(J, W, P, Q, xi, M_o, g_o, scale * effort)
        assert E.empty == empty
        np.testing.assert_allclose(E.center, reference(scale)[1], rtol=1e-9)
        assert np.all(np.isfinite(E.matrix)) and np.all(np.isfinite(E.semi_axes))


def test_kinematic_ellipsoid_function_on_arrays(rng):
    """kinematic_ellipsoid on arrays: full row rank gives (J_hat^+ W^T)^T (J_hat^+ W^T); a rank-deficient
    J_hat (one arm's rows repeated) gives the image of the consistent unit ball."""
    from mobmanip.sets.ellipsoid import kinematic_ellipsoid

    J, W, *_ = _synthetic_problem(rng)
    limits = rng.uniform(0.5, 3.0, size=J.shape[1])
    J_hat = J * limits
    B = np.linalg.pinv(J_hat) @ W.T
    assert _rel(kinematic_ellipsoid(J, W, limits).matrix, B.T @ B) < RTOL
    J_low = J.copy()
    J_low[3:] = J_low[:3]  # both hands move alike: J_hat has rank 3 only
    N, T = _consistent_motions(J_low * limits, W)
    K = T @ N
    _same_ellipsoid(kinematic_ellipsoid(J_low, W, limits), np.zeros(3), K @ K.T)


def test_dynamic_ellipsoids_grow_with_wheel_torque(paper, q0):
    """Z_w decreases with the wheel torque, so ||Z Lambda a|| decreases pointwise: nested sets."""
    for decoupled in (False, True):
        previous = None
        for torque in (10.0, 50.0, 200.0, 1000.0):
            A = analyze(paper.with_wheel_limits(effort=torque), q0, "planar", decoupled=decoupled).dynamic.matrix
            if previous is not None:
                assert np.linalg.eigvalsh(previous - A).min() >= -1e-12 * np.abs(previous).max()
            previous = A


# =============================================================================================
# Rotating the whole robot.


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_turning_the_robot_turns_both_ellipsoids(paper, task, rng):
    base = analyze(paper, paper.configuration(POSE, JOINTS), task)
    for _ in range(3):
        x, y, dyaw = rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-math.pi, math.pi)
        turned = analyze(paper, paper.configuration((x, y, POSE[2] + dyaw), JOINTS), task)
        c, s = math.cos(dyaw), math.sin(dyaw)
        Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        rows = list(TASK_ROWS[task])
        R = scipy.linalg.block_diag(Rz, Rz)[np.ix_(rows, rows)]
        # Nothing in the reduced dynamics depends on where the platform is or where it points.
        np.testing.assert_allclose(turned.reduced_inertia, base.reduced_inertia, rtol=0, atol=1e-10)
        np.testing.assert_array_equal(turned.input_matrix, base.input_matrix)
        np.testing.assert_allclose(turned.bias, base.bias, rtol=0, atol=1e-10)
        for E0, E1 in ((base.kinematic, turned.kinematic), (base.dynamic, turned.dynamic)):
            np.testing.assert_allclose(E1.semi_axes, E0.semi_axes, rtol=1e-9, atol=1e-12 * E0.semi_axes[0])
            assert E1.degenerate == E0.degenerate and E1.empty == E0.empty
            np.testing.assert_allclose(E1.center, R @ E0.center, rtol=0, atol=1e-9)
            scale = np.abs(E0.matrix).max()
            np.testing.assert_allclose(E1.matrix, R @ E0.matrix @ R.T, rtol=0, atol=1e-9 * scale)
            G0, G1 = E0.generator, E1.generator
            np.testing.assert_allclose(G1 @ G1.T, R @ G0 @ G0.T @ R.T, rtol=0, atol=1e-9 * E0.semi_axes[0] ** 2)
            for k in range(E0.dim):
                gaps = np.abs(E0.semi_axes - E0.semi_axes[k])
                gaps[k] = np.inf
                if gaps.min() > 1e-6 * E0.semi_axes[0]:  # axis defined up to sign
                    assert abs(E1.axes[k] @ (R @ E0.axes[k])) == pytest.approx(1.0, abs=1e-9)


# =============================================================================================
# Degenerate: both arms stretched along the same direction.


def test_stretched_arms_give_a_flat_ellipsoid(paper, own):
    """Both arms straight along u (q2 = q3 = 0, same q1): the tips coincide 1.5 m out and can only
    move across u. Locked platform: zero semi-axis along u; the other one by hand."""
    theta = 0.7
    u = np.array([math.cos(theta), math.sin(theta)])
    n = np.array([-u[1], u[0]])
    joints = dict(zip(RIGHT + LEFT, (theta, 0.0, 0.0, theta, 0.0, 0.0)))
    locked = paper.with_platform("fixed")
    an = analyze(locked, locked.configuration((0.0, 0.0, 0.0), joints), "planar")
    for E in (an.kinematic, an.dynamic):
        assert E.degenerate and not E.empty
        assert E.semi_axes[1] == 0.0 and E.semi_axes[0] > 0.0
        assert abs(E.axes[1] @ u) == pytest.approx(1.0, abs=1e-9)
        document = E.to_dict()
        assert document.pop("kind") == "ellipsoid"
        for value in document.values():
            assert np.all(np.isfinite(value))
        assert E.contains(0.9 * E.semi_axes[0] * n)
        assert not E.contains(1e-6 * u) and not E.contains(0.5 * E.semi_axes[0] * n + 1e-6 * u)
        json.dumps(E.to_dict(), allow_nan=False)
    # Kinematic: each arm moves its tip across u at j . qbar_i with j = 3.14 (1.5, 1.0, 0.5) (joint i's
    # distance to the tip); both must agree, so the cheapest unit-norm motion gives |v| = |j| / sqrt(2).
    j = ARM_SPEED * np.cumsum(LINK_LENGTHS[::-1])[::-1]
    assert an.kinematic.semi_axes[0] == pytest.approx(np.linalg.norm(j) / math.sqrt(2), rel=1e-9)
    # Dynamic: a = s n needs tau = s Lambda n, so the semi-axis is 1 / |Z Lambda n| (Lambda from the
    # arms' own Jacobians and mass block).
    q = own.q((0.0, 0.0, 0.0), joints)
    J = scipy.linalg.block_diag(
        own.arm_jacobian(q, TOOLS[0], RIGHT, (0, 1)), own.arm_jacobian(q, TOOLS[1], LEFT, (0, 1))
    )
    W = np.hstack([np.eye(2), np.eye(2)])
    J_pinv = np.linalg.pinv(J, rcond=1e-10)  # J has rank 2 exactly: drop the round-off singular values
    Lam = own.mass_block(q, RIGHT + LEFT) @ J_pinv @ W.T + J.T @ np.linalg.pinv(W) @ (2.0 * np.eye(2))
    Z = 1.0 / np.array(ARM_TORQUE * 2)
    assert an.dynamic.semi_axes[0] == pytest.approx(1.0 / np.linalg.norm(Z * (Lam @ n)), rel=1e-9)

    # The mobile platform lifts the degeneracy when u is the heading: along u only the wheels help,
    # forward speed (rim_r + rim_l) / 2 with unit rim speeds -> |v| = 1 / sqrt(2) m/s at unit norm.
    joints0 = dict(zip(RIGHT + LEFT, (0.0,) * 6))
    mobile = analyze(paper, paper.configuration((0.0, 0.0, 0.0), joints0), "planar")
    assert not mobile.kinematic.degenerate
    assert mobile.kinematic.radius_along(np.array([1.0, 0.0])) == pytest.approx(1 / math.sqrt(2), rel=1e-9)


def _near_stretched_reference(own, eps):
    """Both arms almost straight (q2 = q3 = eps) along theta = 0.7 on the locked platform, with the
    paper's dynamic set rebuilt from each arm's own Jacobian: J has full row rank (smallest singular
    value ~0.6 eps), so J^+ = blockdiag(J_1^+, J_2^+) and every object acceleration is reachable."""
    joints = dict(zip(RIGHT + LEFT, (0.7, eps, eps, 0.7, eps, eps)))
    q = own.q((0.0, 0.0, 0.0), joints)
    J1 = own.arm_jacobian(q, TOOLS[0], RIGHT, (0, 1))
    J2 = own.arm_jacobian(q, TOOLS[1], LEFT, (0, 1))
    J = scipy.linalg.block_diag(J1, J2)
    W = np.hstack([np.eye(2), np.eye(2)])
    J_pinv = scipy.linalg.block_diag(np.linalg.pinv(J1), np.linalg.pinv(J2))
    Lam = own.mass_block(q, RIGHT + LEFT) @ J_pinv @ W.T + J.T @ np.linalg.pinv(W) @ (2.0 * np.eye(2))
    L = Lam / np.array(ARM_TORQUE * 2)[:, None]
    return joints, 1.0 / np.linalg.svd(L, compute_uv=False)[::-1]  # semi-axes, descending


@pytest.mark.parametrize("eps", [1e-3, 1e-5, 1e-6])
def test_dynamic_ellipsoid_next_to_a_singularity(paper, own, eps):
    """Close to (not at) the stretched posture the set is a thin ellipse: major axis ~ 36 m/s^2,
    minor axis ~ 28 eps m/s^2 (J^+ ~ 1 / eps across). Reference accurate to ~cond(J) 1e-16 ~ 1e-9."""
    locked = paper.with_platform("fixed")
    joints, semi = _near_stretched_reference(own, eps)
    E = analyze(locked, locked.configuration((0.0, 0.0, 0.0), joints), "planar").dynamic
    np.testing.assert_allclose(E.semi_axes, semi, rtol=1e-6)


@pytest.mark.parametrize("eps", [1e-8, 1e-9])
def test_dynamic_ellipsoid_does_not_collapse_just_next_to_a_singularity(paper, own, eps):
    locked = paper.with_platform("fixed")
    joints, semi = _near_stretched_reference(own, eps)
    E = analyze(locked, locked.configuration((0.0, 0.0, 0.0), joints), "planar").dynamic
    # Only the major axis is checked: at cond(J) ~ 3e8 the reference's minor axis is good to ~1e-7 only.
    assert E.semi_axes[0] == pytest.approx(semi[0], rel=1e-6)


# =============================================================================================
# Gravity: small fixed-base arms written to tmp_path (horizontal joint axes, task translational).

Y_AXIS = (0, 1, 0)


def _chain_urdf(arms) -> str:
    """URDF text for arms of revolute joints on a fixed 'base_link'.

    arms: (prefix, joint origin, links) with links: (axis, next origin, com, mass, (ixx, iyy, izz),
    effort limit); the last 'next origin' places the fixed tool frame '<prefix>_tool'.
    """

    def xyz(v):
        return " ".join(repr(float(c)) for c in v)

    out = [
        '<?xml version="1.0"?>',
        '<robot name="gravity_arms">',
        '<link name="base_link"><inertial><origin xyz="0 0 0"/><mass value="10"/>'
        '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>',
    ]
    for prefix, origin, links in arms:
        parent = "base_link"
        for k, (axis, next_origin, com, mass, inertia, effort) in enumerate(links, 1):
            link = f"{prefix}_{k}_link"
            out.append(
                f'<joint name="{prefix}_{k}_joint" type="revolute"><parent link="{parent}"/><child link="{link}"/>'
                f'<origin xyz="{xyz(origin)}" rpy="0 0 0"/><axis xyz="{xyz(axis)}"/>'
                f'<limit lower="-3.14" upper="3.14" effort="{effort!r}" velocity="2.0"/></joint>'
            )
            out.append(
                f'<link name="{link}"><inertial><origin xyz="{xyz(com)}" rpy="0 0 0"/><mass value="{mass!r}"/>'
                f'<inertia ixx="{inertia[0]!r}" ixy="0" ixz="0" iyy="{inertia[1]!r}" iyz="0" izz="{inertia[2]!r}"/>'
                "</inertial></link>"
            )
            parent, origin = link, next_origin
        out.append(
            f'<joint name="{prefix}_tool_joint" type="fixed"><parent link="{parent}"/><child link="{prefix}_tool"/>'
            f'<origin xyz="{xyz(origin)}" rpy="0 0 0"/></joint><link name="{prefix}_tool"/>'
        )
    out.append("</robot>")
    return "\n".join(out)


def _gravity_robot(tmp_path: Path, name: str, arms):
    (tmp_path / f"{name}.urdf").write_text(_chain_urdf(arms))
    lines = [f'name = "{name}"', f'urdf = "{name}.urdf"', 'platform = "fixed"', 'default_task = "translational"', ""]
    for prefix, _, links in arms:
        joints = ", ".join(f'"{prefix}_{k}_joint"' for k in range(1, len(links) + 1))
        lines += ["[[arms]]", f'name = "{prefix}"', f"joints = [{joints}]", f'end_effector = "{prefix}_tool"', ""]
    robot = mobmanip.load_robot(_write_spec(tmp_path, name, "\n".join(lines)))
    own_model = pin.buildModelFromUrdf(str(tmp_path / f"{name}.urdf"))  # fixed base, no root joint
    return robot, own_model


TWO_LINK = [
    (
        "a",
        (0.0, 0.0, 1.0),
        [
            (Y_AXIS, (0.5, 0.0, 0.0), (0.25, 0.0, 0.0), 4.0, (0.01, 0.1, 0.1), 150.0),
            (Y_AXIS, (0.4, 0.0, 0.0), (0.2, 0.0, 0.0), 2.0, (0.01, 0.03, 0.03), 60.0),
        ],
    )
]
THREE_LINK = [
    (
        "a",
        (0.0, 0.0, 1.0),
        [
            (Y_AXIS, (0.5, 0.0, 0.0), (0.25, 0.0, 0.0), 4.0, (0.01, 0.1, 0.1), 150.0),
            (Y_AXIS, (0.4, 0.0, 0.0), (0.2, 0.0, 0.0), 2.0, (0.01, 0.03, 0.03), 60.0),
            (Y_AXIS, (0.3, 0.0, 0.0), (0.15, 0.0, 0.0), 1.0, (0.01, 0.01, 0.01), 20.0),
        ],
    )
]


def _tool_jacobian(model, q, tool):
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    frame = model.getFrameId(tool)
    return pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)[:3], data.oMf[frame]


@pytest.mark.parametrize("load", [0.0, 1.5, 6.0])
def test_gravity_shifts_the_centre_to_the_zero_torque_acceleration(tmp_path, load, rng):
    """Square case (2 joints, the tip moves in the x-z plane): the centre is the acceleration with zero
    torque, i.e. the arm and its load falling. Reference: the load appended to the last link as a point
    mass and Pinocchio's articulated-body forward dynamics (no paper formula involved)."""
    robot, model = _gravity_robot(tmp_path, "two_link", TWO_LINK)
    joints = {"a_1_joint": -0.3, "a_2_joint": 0.8}
    q = robot.configuration((0.0, 0.0, 0.0), joints)
    an = analyze(robot, q, "translational", object_mass=load)
    E = an.dynamic

    q_own = np.array([joints["a_1_joint"], joints["a_2_joint"]])
    J, tool = _tool_jacobian(model, q_own, "a_tool")
    loaded = model.copy()
    last = loaded.getJointId("a_2_joint")
    tool_in_joint = loaded.frames[loaded.getFrameId("a_tool")].placement.translation
    loaded.inertias[last] = loaded.inertias[last] + pin.Inertia(load, tool_in_joint, np.zeros((3, 3)))
    data = loaded.createData()
    qdd_free = pin.aba(loaded, data, q_own, np.zeros(2), np.zeros(2))
    falling = J @ qdd_free
    np.testing.assert_allclose(E.center, falling, rtol=1e-9, atol=1e-9)
    assert E.center[2] < -1.0  # pulled downward
    assert abs(E.center[1]) < 1e-12

    # The whole set: a = J q_dd with tau = M_load q_dd + g_load, ||Z tau|| <= 1 (a in the x-z plane).
    M = pin.crba(loaded, data, q_own)
    M = np.triu(M) + np.triu(M, 1).T
    g = pin.computeGeneralizedGravity(loaded, data, q_own)
    Z = 1.0 / np.array([150.0, 60.0])
    J_xz = J[[0, 2]]
    assert E.degenerate and E.semi_axes[2] == 0.0 and abs(E.axes[2][1]) == pytest.approx(1.0)
    for a in E.center + _unit(rng, 200, 2) @ E.generator[:, :2].T:  # unit z on the two non-zero axes
        assert abs(a[1]) < 1e-12
        tau = M @ np.linalg.solve(J_xz, a[[0, 2]]) + g
        assert np.linalg.norm(Z * tau) == pytest.approx(1.0, abs=ON_BOUNDARY)
    assert not E.contains(E.center + np.array([0.0, 1e-6, 0.0]))


def _own_dynamic_set(model, q_own, tools_and_joints, mass, effort):
    """Lambda_o, mu_o of one arm holding a point load (W = I), from the own Pinocchio model."""
    data = model.createData()
    J, _ = _tool_jacobian(model, q_own, tools_and_joints)
    M = pin.crba(model, data, q_own)
    M = np.triu(M) + np.triu(M, 1).T
    g = pin.computeGeneralizedGravity(model, data, q_own)
    g_o = np.array([0.0, 0.0, mass * G])
    Lam = M @ np.linalg.pinv(J) + J.T @ (mass * np.eye(3))
    mu = g + J.T @ g_o  # -xi = +g at rest
    return Lam, mu, 1.0 / np.asarray(effort), J


def test_redundant_arm_under_gravity_centre_and_emptiness(tmp_path):
    """Three joints moving the tip in the x-z plane: more torques than accelerations, so part of the
    holding torque cannot be cancelled by accelerating. Centre = -L^+ Z mu on the feasible plane,
    A = L^T L / (1 - |r|^2), and the set is empty once |r| >= 1 (r: the part of Z mu outside range(L)).

    A heavier load alone does not empty the set: a heavy load may simply fall (a_o -> -g needs no
    torque), so r stays bounded as the mass grows. Weaker motors do: scaling every effort limit by s
    scales r by 1 / s, so with the limits' r = r_1 the set is empty exactly for s <= |r_1|.
    """
    robot, model = _gravity_robot(tmp_path, "three_link", THREE_LINK)
    names = ("a_1_joint", "a_2_joint", "a_3_joint")
    values = (-0.2, 0.9, -0.6)
    q = robot.configuration((0.0, 0.0, 0.0), dict(zip(names, values)))
    q_own = np.array(values)
    effort = np.array([150.0, 60.0, 20.0])
    plane = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0]])  # x-z plane: where the tip can accelerate

    def residual(mass, scale=1.0):
        Lam, mu, Z, _ = _own_dynamic_set(model, q_own, "a_tool", mass, scale * effort)
        L = Z[:, None] * Lam @ plane
        mu_bar = Z * mu
        r = mu_bar - L @ np.linalg.lstsq(L, mu_bar, rcond=None)[0]
        return L, mu_bar, r

    for mass in (0.0, 1.0, 2.5):
        E = analyze(robot, q, "translational", object_mass=mass).dynamic
        L, mu_bar, r = residual(mass)
        assert 1e-4 < r @ r < 1.0  # a genuine, feasible offset
        centre = plane @ (-np.linalg.pinv(L) @ mu_bar)
        np.testing.assert_allclose(E.center, centre, rtol=1e-9, atol=1e-9)
        shape_inv = plane @ (L.T @ L / (1.0 - r @ r)) @ plane.T
        assert _rel(E.matrix, shape_inv) < RTOL
        assert not E.empty and E.degenerate and E.semi_axes[1] > 0.0  # flat across y only
    # A heavy load falls: |r| stays below one however heavy (checked up to 1000 kg).
    assert all(np.linalg.norm(residual(mass)[2]) < 1.0 for mass in (10.0, 100.0, 1000.0))
    assert not analyze(robot, q, "translational", object_mass=1000.0).dynamic.empty

    mass = 2.5
    threshold = float(np.linalg.norm(residual(mass)[2]))
    np.testing.assert_allclose(np.linalg.norm(residual(mass, threshold)[2]), 1.0, rtol=1e-12)
    for scale, empty in ((threshold * (1 + 1e-6), False), (threshold * (1 - 1e-6), True)):
        weak = robot.with_limits(effort=dict(zip(names, scale * effort)))
        an = analyze(weak, q, "translational", object_mass=mass)
        assert an.dynamic.empty == empty
        if empty:
            assert np.all(an.dynamic.semi_axes == 0.0)
            assert not an.dynamic.contains(an.dynamic.center)
            # the reported centre is still the least-violating acceleration
            L, mu_bar, _ = residual(mass, scale)
            expected = plane @ (-np.linalg.pinv(L) @ mu_bar)  # its y entry is 0: held to the centre's own scale
            np.testing.assert_allclose(an.dynamic.center, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
            _assert_no_nan(an)
        else:
            assert an.dynamic.semi_axes[1] > 0.0


def _assert_no_nan(an):
    data = an.to_dict()
    text = json.dumps(data, allow_nan=False)  # raises on NaN or infinity
    assert "NaN" not in text
    for E in (an.kinematic, an.dynamic):
        for field in (E.center, E.semi_axes, E.axes, E.matrix):
            assert np.all(np.isfinite(field))
        assert math.isfinite(E.volume) and math.isfinite(E.isotropy)


def test_threshold_mass_matches_the_static_torque_balance(tmp_path):
    """Two single-link arms grip one point: arm A horizontal (its tip moves only in z), arm B hanging
    vertically (its tip moves only in x). No object acceleration is compatible with both, so the set
    is at most the point a_o = 0 and is empty exactly when holding still exceeds a torque limit.

    With W = [I I], W^+ splits the weight equally; arm B carries its half along its link (no torque),
    arm A needs tau_A = m g L / 2 + m_1 g L_c1. So the threshold is m* = 2 (tau_A,max - m_1 g L_c1) / (g L).
    """
    L_a, Lc_a, m_a, tau_a = 0.5, 0.25, 3.0, 40.0
    arms = [
        ("a", (0.0, 0.0, 1.0), [(Y_AXIS, (L_a, 0.0, 0.0), (Lc_a, 0.0, 0.0), m_a, (0.01, 0.08, 0.08), tau_a)]),
        ("b", (0.5, 0.0, 1.5), [(Y_AXIS, (0.0, 0.0, -0.5), (0.0, 0.0, -0.25), 2.0, (0.05, 0.05, 0.01), 40.0)]),
    ]
    robot, _ = _gravity_robot(tmp_path, "two_arms", arms)
    q = robot.configuration((0.0, 0.0, 0.0), {})
    threshold = 2.0 * (tau_a - m_a * G * Lc_a) / (G * L_a)
    hold = analyze(robot, q, "translational", object_mass=0.5 * threshold)
    np.testing.assert_allclose(hold.held_object.offsets, 0.0, atol=1e-12)  # the tips do coincide
    assert not hold.dynamic.empty
    assert np.all(hold.dynamic.semi_axes == 0.0) and hold.dynamic.degenerate
    assert hold.dynamic.contains(np.zeros(3)) and not hold.dynamic.contains(np.array([1e-6, 0.0, 0.0]))
    assert not analyze(robot, q, "translational", object_mass=threshold * (1 - 1e-6)).dynamic.empty
    heavy = analyze(robot, q, "translational", object_mass=threshold * (1 + 1e-6))
    assert heavy.dynamic.empty
    _assert_no_nan(heavy)
    _assert_no_nan(hold)
