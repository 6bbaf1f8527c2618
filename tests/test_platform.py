"""The differential-drive constraint layer: paper form (Eq. 4-11) and Pinocchio form agree.

Pinocchio's planar root joint moves with (v_x, v_y, omega_z) in the platform frame, so the
constant S maps wheel rates to those and to the wheel joints. The paper writes the same
constraints in world coordinates vq = [x_o, y_o, theta_r, theta_l] with heading
phi = c (theta_r - theta_l). These tests check each form on its own and then integrate both
from the same start to check they describe the same motion.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import (
    HALF_TRACK,
    OFFSET_AXLE,
    WHEEL_RADIUS,
    flipped_wheel_urdf,
    offset_axle_urdf,
    random_configuration,
    write_variant,
)

# Relative size of round-off in the small (<= 11 x 8) matrix products below: a few hundred ulps.
ROUND_OFF = 1e-13


def wrap(angle):
    """Angle(s) wrapped to (-pi, pi]."""
    return np.angle(np.exp(1j * np.asarray(angle)))


@pytest.fixture(scope="module")
def variants(robot, tmp_path_factory):
    """The paper robot and URDF variants that exercise the signs and the axle offset."""
    tmp = tmp_path_factory.mktemp("platform_variants")
    return {
        "paper": robot,
        "flipped_left": mobmanip.load_robot(write_variant(tmp, flipped_wheel_urdf("left"), name="flipped_left")),
        "flipped_right": mobmanip.load_robot(write_variant(tmp, flipped_wheel_urdf("right"), name="flipped_right")),
        "offset_axle": mobmanip.load_robot(write_variant(tmp, offset_axle_urdf(), name="offset_axle")),
    }


VARIANTS = ("paper", "flipped_left", "flipped_right", "offset_axle")


def wheel_joint_angle(robot, q, side):
    """A wheel joint's angle (rad, wrapped) read from q (continuous joint: cos, sin)."""
    joint = robot.model.joints[robot.model.getJointId(f"wheel_{side}_joint")]
    return math.atan2(q[joint.idx_q + 1], q[joint.idx_q])


def axle_centre_in_world(robot, q):
    """World (x, y) of P_o: the platform origin plus the rotated axle offset."""
    px, py = robot.platform.axle_center
    c, s = q[2], q[3]
    return np.array([q[0] + c * px - s * py, q[1] + s * px + c * py])


# ----- the paper's world-frame form -----


def test_paper_null_space_spans_kernel_of_constraints(robot, rng):
    platform = robot.platform
    for _ in range(50):
        theta_r, theta_l = rng.uniform(-20.0, 20.0, size=2)
        phi = platform.heading(theta_r, theta_l)
        A = platform.constraint_matrix_paper(phi)
        S = platform.null_space_paper(phi)
        assert A.shape == (2, 4) and S.shape == (4, 2)
        # Entries are O(r) = O(0.1); A S = 0 holds up to round-off.
        np.testing.assert_allclose(A @ S, 0.0, atol=ROUND_OFF)
        # rank A = 2 and rank S = 2 = 4 - rank A: the columns of S span the whole null space.
        assert np.linalg.matrix_rank(A) == 2
        assert np.linalg.matrix_rank(S) == 2


def test_paper_constraints_are_eq_5_and_6(robot, rng):
    """A vq_dot = 0 is exactly no lateral slip (Eq. 5) and no longitudinal slip (Eq. 6)."""
    platform = robot.platform
    c, b = platform.c, platform.half_track
    for _ in range(20):
        phi = rng.uniform(-math.pi, math.pi)
        vq_dot = rng.normal(size=4)
        lateral = vq_dot[0] * math.sin(phi) - vq_dot[1] * math.cos(phi)
        longitudinal = vq_dot[0] * math.cos(phi) + vq_dot[1] * math.sin(phi) - c * b * (vq_dot[2] + vq_dot[3])
        residual = platform.constraint_matrix_paper(phi) @ vq_dot
        # Each row may differ from the printed equation by a sign, never by more.
        assert abs(abs(residual[0]) - abs(lateral)) < ROUND_OFF
        assert abs(abs(residual[1]) - abs(longitudinal)) < ROUND_OFF


def test_paper_constants(robot):
    platform = robot.platform
    assert platform.radius == pytest.approx(WHEEL_RADIUS, abs=1e-12)
    assert platform.half_track == pytest.approx(HALF_TRACK, abs=1e-12)
    assert platform.c == pytest.approx(WHEEL_RADIUS / (2 * HALF_TRACK), rel=1e-12)
    assert platform.heading(1.0, 0.0) == pytest.approx(WHEEL_RADIUS / (2 * HALF_TRACK), rel=1e-12)


def test_null_space_rate_matches_finite_differences(robot, rng):
    platform = robot.platform
    # Central differences err by h^2/6 |d^3 S/dt^3| <= h^2/6 (r/2) phi_dot^3 <= 1e-10/6 * 0.0375 * 5.7^3 ~ 1.2e-10
    # (|phi_dot| <= c * 26 ~ 5.7 rad/s); round-off is ~ eps |S| / h ~ 1e-12. 1e-9 bounds both.
    h = 1e-5
    for _ in range(20):
        theta = rng.uniform(-10.0, 10.0, size=2)
        eta = rng.uniform(-13.0, 13.0, size=2)
        phi = platform.heading(*theta)
        phi_dot = platform.c * (eta[0] - eta[1])
        finite = (platform.null_space_paper(phi + phi_dot * h) - platform.null_space_paper(phi - phi_dot * h)) / (2 * h)
        # Along the motion theta moves by eta h, so also phi = c (theta_r - theta_l) through heading().
        phi_plus = platform.heading(*(theta + eta * h))
        phi_minus = platform.heading(*(theta - eta * h))
        finite_heading = (platform.null_space_paper(phi_plus) - platform.null_space_paper(phi_minus)) / (2 * h)
        rate = platform.null_space_rate_paper(phi, eta)
        np.testing.assert_allclose(rate, finite, atol=1e-9)
        np.testing.assert_allclose(rate, finite_heading, atol=1e-9)


# ----- the Pinocchio form -----


@pytest.mark.parametrize("name", VARIANTS)
def test_S_has_full_column_rank(variants, name):
    robot = variants[name]
    S = robot.S
    assert S.shape == (robot.model.nv, robot.nx)
    assert np.linalg.matrix_rank(S) == robot.nx
    # Well conditioned too: its smallest singular value is of the order of r/2 or 1.
    assert np.linalg.svd(S, compute_uv=False).min() > 0.01


@pytest.mark.parametrize("name", VARIANTS)
def test_S_satisfies_no_slip_at_the_axle_and_rolling_at_each_wheel(variants, name, rng):
    robot = variants[name]
    platform = robot.platform
    r, b = WHEEL_RADIUS, HALF_TRACK
    px, py = platform.axle_center
    right_v, left_v = platform.wheel_v
    for _ in range(20):
        x = rng.uniform(-10.0, 10.0, size=robot.nx)
        v = robot.S @ x
        vx, vy, omega = v[0], v[1], v[2]
        # Velocity of a point p of the platform, in the platform frame: (vx - omega p_y, vy + omega p_x).
        assert vy + omega * px == pytest.approx(0.0, abs=1e-12)  # no lateral slip at P_o
        forward_right = vx - omega * (py - b)  # right wheel centre at P_o - b y
        forward_left = vx - omega * (py + b)
        assert forward_right == pytest.approx(r * x[0], abs=1e-12)
        assert forward_left == pytest.approx(r * x[1], abs=1e-12)
        # Each wheel joint turns at the wheel rate, in the joint's own sense.
        assert v[right_v] == pytest.approx(platform.signs[0] * x[0], abs=1e-12)
        assert v[left_v] == pytest.approx(platform.signs[1] * x[1], abs=1e-12)
        # The arm joints move with their own rates.
        np.testing.assert_array_equal(v[list(robot.arm_v_indices)], x[2:])


def test_offset_axle_is_read_from_the_urdf(variants):
    platform = variants["offset_axle"].platform
    np.testing.assert_allclose(platform.axle_center, OFFSET_AXLE, atol=1e-12)
    assert platform.half_track == pytest.approx(HALF_TRACK, abs=1e-12)


@pytest.mark.parametrize("name", VARIANTS)
def test_wheel_contact_points_do_not_slip(variants, name, rng):
    """Independent of S's formula: Pinocchio's own wheel velocities give zero contact-point velocity."""
    robot = variants[name]
    model = robot.model
    data = model.createData()
    for _ in range(10):
        q = random_configuration(robot, rng)
        x = rng.uniform(-10.0, 10.0, size=robot.nx)
        v = robot.S @ x
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        for side in ("right", "left"):
            frame = model.getFrameId(f"wheel_{side}_link")
            twist = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            # Contact point: r straight below the wheel centre (world axes).
            contact = twist.linear + np.cross(twist.angular, [0.0, 0.0, -WHEEL_RADIUS])
            # Speeds are O(1) m/s: round-off is ~1e-15.
            np.testing.assert_allclose(contact, 0.0, atol=1e-12)


# ----- both forms describe the same motion -----


def integrate_paper_rk4(platform, vq0, eta, duration, steps):
    """Classical RK4 on vq_dot = S_paper(phi(vq)) eta, phi = c (theta_r - theta_l)."""

    def rhs(vq):
        return platform.null_space_paper(platform.heading(vq[2], vq[3])) @ eta

    vq = np.array(vq0, dtype=float)
    dt = duration / steps
    for _ in range(steps):
        k1 = rhs(vq)
        k2 = rhs(vq + 0.5 * dt * k1)
        k3 = rhs(vq + 0.5 * dt * k2)
        k4 = rhs(vq + dt * k3)
        vq = vq + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return vq


@pytest.mark.parametrize("name", VARIANTS)
def test_pinocchio_and_paper_forms_integrate_to_the_same_pose(variants, name, rng):
    robot = variants[name]
    platform = robot.platform
    duration, steps = 1.5, 1500
    for _ in range(3):
        # Start: wheel angles (forward sense) fix the heading through the holonomic relation.
        theta0 = rng.uniform(-math.pi, math.pi, size=2)
        phi0 = platform.heading(*theta0)
        xo0 = rng.uniform(-2.0, 2.0, size=2)
        eta = rng.uniform(-12.0, 12.0, size=2)

        # Pinocchio: base origin = P_o - R(phi0) p; wheel joint angle = sign * theta.
        px, py = platform.axle_center
        c0, s0 = math.cos(phi0), math.sin(phi0)
        origin = xo0 - np.array([c0 * px - s0 * py, s0 * px + c0 * py])
        q0 = robot.configuration(
            platform=(origin[0], origin[1], phi0),
            joints={
                "wheel_right_joint": platform.signs[0] * theta0[0],
                "wheel_left_joint": platform.signs[1] * theta0[1],
            },
        )
        x = np.zeros(robot.nx)
        x[:2] = eta
        # Exact: the body twist S x is constant, and the planar joint integrates it on SE(2).
        qT = pin.integrate(robot.model, q0, robot.S @ x * duration)

        vqT = integrate_paper_rk4(platform, [xo0[0], xo0[1], theta0[0], theta0[1]], eta, duration, steps)

        # theta is linear in t, so RK4 here is Simpson's rule on v(t) (cos phi, sin phi): its error is at most
        # T dt^4 / 2880 * |v| phi_dot^4 <= 1.5 * 1e-12 / 2880 * 0.9 * 5.3^4 ~ 4e-13 m (|phi_dot| <= c * 24).
        # 1e-10 m leaves room for round-off over 1500 steps; a wrong sign or factor errs by ~0.1 m.
        np.testing.assert_allclose(axle_centre_in_world(robot, qT), vqT[:2], atol=1e-10)
        # theta_dot = eta is constant, so RK4 integrates the wheel angles exactly (round-off only).
        assert wrap(wheel_joint_angle(robot, qT, "right") - platform.signs[0] * vqT[2]) == pytest.approx(0, abs=1e-10)
        assert wrap(wheel_joint_angle(robot, qT, "left") - platform.signs[1] * vqT[3]) == pytest.approx(0, abs=1e-10)
        # Heading: Pinocchio's yaw against the paper's phi = c (theta_r - theta_l).
        yaw = math.atan2(qT[3], qT[2])
        assert wrap(yaw - platform.heading(vqT[2], vqT[3])) == pytest.approx(0, abs=1e-10)


@pytest.mark.parametrize("name", VARIANTS)
def test_holonomic_relation_holds_after_integration(variants, name, rng):
    """phi(T) - phi(0) = c (delta theta_r - delta theta_l), read back from Pinocchio's q alone."""
    robot = variants[name]
    platform = robot.platform
    for _ in range(10):
        q0 = random_configuration(robot, rng)
        x = rng.uniform(-1.0, 1.0, size=robot.nx)
        # Short enough that no angle change exceeds pi, so wrapped differences are the true ones.
        duration = 0.25
        qT = pin.integrate(robot.model, q0, robot.S @ x * duration)
        d_yaw = wrap(math.atan2(qT[3], qT[2]) - math.atan2(q0[3], q0[2]))
        d_right = platform.signs[0] * wrap(
            wheel_joint_angle(robot, qT, "right") - wheel_joint_angle(robot, q0, "right")
        )
        d_left = platform.signs[1] * wrap(wheel_joint_angle(robot, qT, "left") - wheel_joint_angle(robot, q0, "left"))
        assert d_yaw == pytest.approx(platform.c * (d_right - d_left), abs=1e-12)
        # And the wheels turned by eta T (in the forward sense).
        assert d_right == pytest.approx(x[0] * duration, abs=1e-12)
        assert d_left == pytest.approx(x[1] * duration, abs=1e-12)


@pytest.mark.parametrize("name", VARIANTS)
def test_positive_wheel_rates_drive_forward(variants, name, rng):
    robot = variants[name]
    platform = robot.platform
    expected_signs = {
        "paper": (1.0, 1.0),
        "flipped_left": (1.0, -1.0),
        "flipped_right": (-1.0, 1.0),
        "offset_axle": (1.0, 1.0),
    }[name]
    assert platform.signs == expected_signs
    for _ in range(5):
        q0 = random_configuration(robot, rng)
        heading = np.array([q0[2], q0[3]])
        x = np.zeros(robot.nx)
        x[:2] = rng.uniform(0.5, 10.0)  # equal positive wheel rates: straight ahead
        duration = 0.1
        qT = pin.integrate(robot.model, q0, robot.S @ x * duration)
        step = axle_centre_in_world(robot, qT) - axle_centre_in_world(robot, q0)
        # Straight line at speed r * eta: forward by exactly r eta T, no sideways motion, no turn.
        assert step @ heading == pytest.approx(WHEEL_RADIUS * x[0] * duration, rel=1e-12)
        assert step @ np.array([-heading[1], heading[0]]) == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(qT[2:4], q0[2:4], atol=1e-14)
        # The wheel joints turned in their own sense: backwards for a flipped axis.
        for k, side in enumerate(("right", "left")):
            turned = wrap(wheel_joint_angle(robot, qT, side) - wheel_joint_angle(robot, q0, side))
            assert turned == pytest.approx(expected_signs[k] * x[k] * duration, abs=1e-12)


@pytest.mark.parametrize("name", VARIANTS)
def test_wheel_rate_difference_turns_left(variants, name, rng):
    """eta_r > eta_l turns the platform counter-clockwise (left) at c (eta_r - eta_l)."""
    robot = variants[name]
    x = np.zeros(robot.nx)
    x[:2] = (2.0, -1.0)
    v = robot.S @ x
    assert v[2] == pytest.approx(WHEEL_RADIUS / (2 * HALF_TRACK) * 3.0, rel=1e-12)


@pytest.mark.parametrize("name", VARIANTS)
def test_wheel_torques_act_in_the_forward_sense(variants, name):
    """Q = S^T B = I whatever the axis signs: a positive wheel torque does positive work on eta."""
    robot = variants[name]
    np.testing.assert_array_equal(robot.S.T @ robot.B, np.eye(robot.nx))
