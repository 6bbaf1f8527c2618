"""Reduced dynamics P, Q, xi and the unified Jacobian J_u, each checked against an independent computation."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

from conftest import HALF_TRACK, WHEEL_RADIUS, random_configuration, random_configurations
from mobmanip.terms.dynamics import decouple, reduced_dynamics, unified_jacobian

# Tables 1 and 2 of the paper.
PLATFORM_MASS, PLATFORM_IZZ = 94.0, 6.609
WHEEL_MASS, WHEEL_I_AXLE, WHEEL_I_DIAMETER = 5.0, 0.01, 0.135
LINK_LENGTH = (0.5, 0.5, 0.5)
LINK_COM = (0.25, 0.25, 0.1)
LINK_MASS = (10.0, 6.0, 2.0)
LINK_IZZ = (0.5, 0.3, 0.01)

# P has entries up to ~10 kg m^2 (wheel block) computed by sums of a few dozen products:
# round-off is ~1e-14 relative; 1e-10 absolute leaves a wide margin and is far below any physical term.
P_TOL = 1e-10


def reduced_velocity(robot, rng):
    """A random reduced velocity within the robot's velocity limits (rad/s)."""
    return rng.uniform(-1.0, 1.0, size=robot.nx) * robot.velocity_limits


# ----- P -----


def test_P_is_symmetric_positive_definite(robot, rng):
    for q in random_configurations(robot, rng, 20):
        P = reduced_dynamics(robot, q).P
        assert P.shape == (robot.nx, robot.nx)
        np.testing.assert_allclose(P, P.T, rtol=0, atol=1e-12)
        # Smallest eigenvalue is physical (~0.017 kg m^2 for the wrist); far above round-off.
        assert np.linalg.eigvalsh(P).min() > 1e-3


def test_P_gives_the_kinetic_energy_of_the_whole_robot(robot, rng):
    """0.5 x^T P x equals Pinocchio's kinetic energy of v = S x (computed without the mass matrix)."""
    data = robot.model.createData()
    for q in random_configurations(robot, rng, 20):
        x = reduced_velocity(robot, rng)
        P = reduced_dynamics(robot, q).P
        energy = pin.computeKineticEnergy(robot.model, data, q, robot.S @ x)
        assert 0.5 * x @ P @ x == pytest.approx(energy, rel=1e-12)


def test_P_columns_from_rnea(robot, rng):
    """P e_k = S^T M S e_k, and M S e_k = rnea(q, 0, S e_k) - rnea(q, 0, 0)."""
    model, data, S = robot.model, robot.model.createData(), robot.S
    zero = np.zeros(model.nv)
    for q in random_configurations(robot, rng, 10):
        P = reduced_dynamics(robot, q).P
        bias = pin.rnea(model, data, q, zero, zero).copy()
        columns = [S.T @ (pin.rnea(model, data, q, zero, S[:, k]) - bias) for k in range(robot.nx)]
        np.testing.assert_allclose(P, np.column_stack(columns), rtol=0, atol=P_TOL)


def planar_reduced_inertia(q_right, q_left):
    """P of the paper's robot derived by hand from Tables 1 and 2 (planar rigid bodies).

    Every body moves in the horizontal plane. A body's planar velocity (v_x, v_y, omega) is
    linear in x = [eta_r, eta_l, right arm q_dot, left arm q_dot]; with the mass-inertia matrix
    diag(m, m, I) about its centre of mass, P = sum J^T diag(m, m, I) J + the wheels' spin I_w.
    Velocities are written in the platform frame (P_o at its origin): the kinetic energy does
    not depend on the frame.
    """
    r, b = WHEEL_RADIUS, HALF_TRACK
    c = r / (2 * b)
    nx = 8
    base = np.zeros((3, nx))  # (v_x, v_y, omega) of P_o in the platform frame
    base[0, :2] = r / 2
    base[2, :2] = (c, -c)

    def point(p, relative=None):
        """Planar velocity rows (v_x, v_y, omega) of a body whose centre of mass is at p, turning with the
        platform, plus its own motion relative to the platform."""
        J = np.zeros((3, nx))
        J[0] = base[0] - p[1] * base[2]
        J[1] = base[1] + p[0] * base[2]
        J[2] = base[2]
        if relative is not None:
            J[:2] += relative
        return J

    bodies = []  # (J, mass, izz)
    bodies.append((point((0.0, 0.0)), PLATFORM_MASS, PLATFORM_IZZ))
    for y in (-b, b):
        bodies.append((point((0.0, y)), WHEEL_MASS, WHEEL_I_DIAMETER))
    for angles, first in ((q_right, 2), (q_left, 5)):
        a = np.cumsum(angles)
        for k in range(3):
            com = sum(LINK_LENGTH[i] * np.array([math.cos(a[i]), math.sin(a[i])]) for i in range(k))
            com = com + LINK_COM[k] * np.array([math.cos(a[k]), math.sin(a[k])])
            relative = np.zeros((2, nx))
            for j in range(k + 1):  # q_j turns every link from j on
                arm = sum(LINK_LENGTH[i] * np.array([-math.sin(a[i]), math.cos(a[i])]) for i in range(j, k))
                relative[:, first + j] = arm + LINK_COM[k] * np.array([-math.sin(a[k]), math.cos(a[k])])
            J = point(com, relative)
            J[2, first : first + k + 1] += 1.0
            bodies.append((J, LINK_MASS[k], LINK_IZZ[k]))
    P = sum(J.T @ np.diag([m, m, izz]) @ J for J, m, izz in bodies)
    P[0, 0] += WHEEL_I_AXLE  # wheel spin about its axle at eta
    P[1, 1] += WHEEL_I_AXLE
    return P


def test_P_matches_the_paper_tables_by_hand(robot, rng):
    for _ in range(10):
        q_right = rng.uniform(-math.pi, math.pi, size=3)
        q_left = rng.uniform(-math.pi, math.pi, size=3)
        joints = {f"arm_right_{k + 1}_joint": q_right[k] for k in range(3)}
        joints |= {f"arm_left_{k + 1}_joint": q_left[k] for k in range(3)}
        joints |= {"wheel_right_joint": rng.uniform(-3, 3), "wheel_left_joint": rng.uniform(-3, 3)}
        q = robot.configuration(platform=tuple(rng.uniform(-3, 3, size=3)), joints=joints)
        np.testing.assert_allclose(reduced_dynamics(robot, q).P, planar_reduced_inertia(q_right, q_left), atol=P_TOL)


def test_arm_arm_blocks_vanish_and_interaction_blocks_do_not(robot, rng):
    """Arms on separate branches do not couple; each arm couples with the platform (the paper's R)."""
    right, left = robot.arm_slices
    for q in random_configurations(robot, rng, 10):
        P = reduced_dynamics(robot, q).P
        np.testing.assert_allclose(P[right, left], 0.0, atol=1e-12)
        # The interaction terms R are physical: of the order of m L^2 c ~ 1 kg m^2 * 0.2.
        assert np.abs(P[:2, right]).max() > 1e-3
        assert np.abs(P[:2, left]).max() > 1e-3


def test_decoupled_P_zeroes_exactly_the_platform_arm_blocks(robot, rng):
    for q in random_configurations(robot, rng, 5):
        P = reduced_dynamics(robot, q).P
        P_dec = reduced_dynamics(robot, q, decoupled=True).P
        np.testing.assert_array_equal(P_dec[:2, 2:], 0.0)
        np.testing.assert_array_equal(P_dec[2:, :2], 0.0)
        np.testing.assert_array_equal(P_dec[:2, :2], P[:2, :2])
        np.testing.assert_array_equal(P_dec[2:, 2:], P[2:, 2:])
        np.testing.assert_array_equal(decouple(robot, P), P_dec)
        assert np.linalg.eigvalsh(P_dec).min() > 0.0


# ----- Q -----


def test_Q_is_the_identity(robot, rng):
    # Q = S^T B: the wheel rows of S are the identity (times the axis signs, as are B's), arms are identity.
    np.testing.assert_array_equal(robot.S.T @ robot.B, np.eye(robot.nx))
    for q in random_configurations(robot, rng, 3):
        np.testing.assert_array_equal(reduced_dynamics(robot, q).Q, np.eye(robot.nx))


# ----- xi -----


def test_xi_is_minus_S_transpose_rnea_at_zero_acceleration(robot, rng):
    """S is constant in Pinocchio's tangent coordinates, so xi = -S^T (C(q, Sx) S x + g) = -S^T rnea(q, Sx, 0)."""
    model, data, S = robot.model, robot.model.createData(), robot.S
    for q in random_configurations(robot, rng, 10):
        x = reduced_velocity(robot, rng)
        xi = reduced_dynamics(robot, q, x).xi
        expected = -S.T @ pin.rnea(model, data, q, S @ x, np.zeros(model.nv))
        # Coriolis terms reach ~1e3 N m at the velocity limits: round-off ~1e-12 relative.
        np.testing.assert_allclose(xi, expected, rtol=0, atol=1e-9)


def test_gravity_does_no_work_on_the_paper_robot(robot, rng):
    """Vertical arm axes, horizontal platform motion and wheels turning about their centre: g(q) = 0."""
    data = robot.model.createData()
    for q in random_configurations(robot, rng, 10):
        g = pin.computeGeneralizedGravity(robot.model, data, q)
        # Weights are ~1e3 N; a gravity term doing work would be ~1e2 N m. Round-off only is left.
        np.testing.assert_allclose(g, 0.0, atol=1e-9)
        np.testing.assert_allclose(reduced_dynamics(robot, q).xi, 0.0, atol=1e-9)


@pytest.fixture(scope="module")
def tilted_robot(robot):
    """The paper robot with gravity tilted out of the vertical, so that gravity does work."""
    model = pin.Model(robot.model)
    model.gravity = pin.Motion(np.array([1.5, -2.0, -9.81]), np.zeros(3))
    return dataclasses.replace(robot, model=model, data=model.createData())


def test_xi_at_rest_is_minus_the_potential_energy_gradient(tilted_robot, rng):
    """xi(q, 0) = -S^T g and g = dV/dq: compare with central differences of V along S e_k."""
    robot = tilted_robot
    model, data, S = robot.model, robot.model.createData(), robot.S
    h = 1e-6
    for q in random_configurations(robot, rng, 5):
        xi = reduced_dynamics(robot, q).xi
        np.testing.assert_allclose(xi, -S.T @ pin.computeGeneralizedGravity(model, data, q), rtol=0, atol=1e-9)
        gradient = np.array(
            [
                (
                    pin.computePotentialEnergy(model, data, pin.integrate(model, q, S[:, k] * h))
                    - pin.computePotentialEnergy(model, data, pin.integrate(model, q, -S[:, k] * h))
                )
                / (2 * h)
                for k in range(robot.nx)
            ]
        )
        # V ~ 1e2 J: round-off eps V / h ~ 1e-8; truncation h^2 |V'''| ~ 1e-12 * 1e2. 1e-6 bounds both.
        np.testing.assert_allclose(xi, -gradient, rtol=0, atol=1e-6)
        assert np.abs(xi).max() > 1.0  # tilted gravity does work: the check is not vacuous


def test_power_of_the_reduced_forces_is_the_rate_of_kinetic_energy(robot, rng):
    """With tau = P xdot - xi (no gravity work, Q = I): x . tau = dT/dt along the motion.

    T(t) = 0.5 x(t)^T P(q(t)) x(t) with q(t +- h) = integrate(q, +-S x h), x(t +- h) = x +- xdot h.
    The curve's tangent at t is (S x, xdot), so the central difference approximates dT/dt with relative
    error ~ h^2/6 * w^2, w ~ 2 rad/s the fastest joint or yaw rate at half the limits: ~1e-8 at h = 1e-4.
    Round-off is eps T / h ~ 1e-16 * 1e2 / 1e-4 = 1e-10 W against a power scale of ~10-100 W.
    Hence a tolerance of 1e-7 of the power scale sum_k |x_k| (|P| |xdot| + |xi|)_k.
    """
    h = 1e-4
    model, S = robot.model, robot.S

    def kinetic(q, x):
        return 0.5 * x @ reduced_dynamics(robot, q).P @ x

    for q in random_configurations(robot, rng, 10):
        x = reduced_velocity(robot, rng) / 2
        xdot = rng.uniform(-5.0, 5.0, size=robot.nx)
        dyn = reduced_dynamics(robot, q, x)
        tau = dyn.P @ xdot - dyn.xi
        finite = (
            kinetic(pin.integrate(model, q, S @ x * h), x + xdot * h)
            - kinetic(pin.integrate(model, q, -S @ x * h), x - xdot * h)
        ) / (2 * h)
        scale = np.abs(x) @ (np.abs(dyn.P) @ np.abs(xdot) + np.abs(dyn.xi))
        assert x @ tau == pytest.approx(finite, abs=1e-7 * scale)


# ----- J_u -----


def end_effector_poses(robot, data, q):
    pin.framesForwardKinematics(robot.model, data, q)
    return [data.oMf[arm.frame_id].copy() for arm in robot.arms]


def finite_difference_twists(robot, q, x, h):
    """Central differences of each end effector's world position and orientation along v = S x."""
    data = robot.model.createData()
    plus = end_effector_poses(robot, data, pin.integrate(robot.model, q, robot.S @ x * h))
    minus = end_effector_poses(robot, data, pin.integrate(robot.model, q, -robot.S @ x * h))
    linear = [(p.translation - m.translation) / (2 * h) for p, m in zip(plus, minus)]
    # R(t+h) R(t-h)^T = exp([omega] 2h) + O(h^3) for the world-frame angular velocity omega.
    angular = [pin.log3(p.rotation @ m.rotation.T) / (2 * h) for p, m in zip(plus, minus)]
    return linear, angular


# Central differences with h = 1e-5: truncation h^2/6 |p'''| <= 1e-10/6 * 1.5 m * (w <= 3 * 3.14 + 0.6 rad/s,
# the summed joint and yaw rates)^3 ~ 2.5e-8 m/s, round-off eps |p| / h ~ 1e-10. Velocities are O(1-10) m/s.
FD_STEP, FD_TOL = 1e-5, 1e-6


@pytest.mark.parametrize("task", ["planar", "translational", "planar_rigid", "spatial"])
def test_unified_jacobian_matches_finite_differences(robot, rng, task):
    rows = {"planar": [0, 1], "translational": [0, 1, 2], "planar_rigid": [0, 1, 5], "spatial": [0, 1, 2, 3, 4, 5]}
    for q in random_configurations(robot, rng, 8):
        x = reduced_velocity(robot, rng)
        J_u = unified_jacobian(robot, q, task)
        assert J_u.shape == (len(rows[task]) * len(robot.arms), robot.nx)
        linear, angular = finite_difference_twists(robot, q, x, FD_STEP)
        expected = np.concatenate([np.concatenate([lin, ang])[rows[task]] for lin, ang in zip(linear, angular)])
        np.testing.assert_allclose(J_u @ x, expected, rtol=0, atol=FD_TOL)


def test_end_effectors_move_in_the_plane_and_turn_about_the_vertical(robot, rng):
    """The spatial rows that must vanish for this planar robot: v_z, omega_x, omega_y."""
    for q in random_configurations(robot, rng, 5):
        J_u = unified_jacobian(robot, q, "spatial")
        for arm in range(len(robot.arms)):
            np.testing.assert_allclose(J_u[6 * arm + np.array([2, 3, 4])], 0.0, atol=1e-12)


# ----- locked platform -----


def test_locked_platform_keeps_only_the_arm_blocks(robot, rng):
    fixed = robot.with_platform("fixed")
    assert fixed.nx == robot.nx - 2
    assert fixed.reduced_velocity_names == robot.reduced_velocity_names[2:]
    model, data = robot.model, robot.model.createData()
    arm_v = list(robot.arm_v_indices)
    for q in random_configurations(robot, rng, 5):
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        dyn = reduced_dynamics(fixed, q)
        np.testing.assert_allclose(dyn.P, M[np.ix_(arm_v, arm_v)], rtol=0, atol=P_TOL)
        np.testing.assert_allclose(dyn.P, reduced_dynamics(robot, q).P[2:, 2:], rtol=0, atol=P_TOL)
        np.testing.assert_array_equal(dyn.Q, np.eye(fixed.nx))
        for task, rows in (("planar", [0, 1]), ("spatial", list(range(6)))):
            own = np.vstack(
                [
                    pin.computeFrameJacobian(model, data, q, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[rows][:, arm_v]
                    for arm in robot.arms
                ]
            )
            np.testing.assert_allclose(unified_jacobian(fixed, q, task), own, rtol=0, atol=1e-12)


def test_locked_platform_jacobian_ignores_the_wheels(robot, rng):
    """Locking the platform removes exactly the wheel columns of the mobile J_u."""
    fixed = robot.with_platform("fixed")
    q = random_configuration(robot, rng)
    np.testing.assert_allclose(
        unified_jacobian(fixed, q, "planar"), unified_jacobian(robot, q, "planar")[:, 2:], rtol=0, atol=1e-12
    )
