"""Motion on the steered platform, the one kind whose S depends on q (Sdot x != 0).

Every other motion test runs on platforms with a constant S, where leaving the Sdot x term out
of the hands' acceleration, the in-motion efforts or the trajectory's acceleration estimates
changes nothing. Here the references are independent of the code under test: a rolling path
q(t) integrated with Pinocchio (``q' = S(q) x(t)``, x(t) = x0 + t xdot, so the platform's
wheels roll without slip along a curve while the steering turns), the hand's position from
forward kinematics differentiated twice by central differences along it, and RNEA at
``(q, S x, S xdot + Sdot x)`` (the joint accelerations of the rolling path, Sdot x included).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.motion import motion_terms
from mobmanip.motion.trajectory import trajectory_from_samples
from mobmanip.terms.dynamics import frame_jacobians
from test_steered import random_state, write_tricycle


@pytest.fixture(scope="module")
def tricycle(tmp_path_factory):
    return mobmanip.load_robot(write_tricycle(tmp_path_factory.mktemp("tricycle_motion")))


def _state(robot, rng):
    """A moving state with the steering away from its limits and the wheels really rolling."""
    q, _ = random_state(robot, rng)
    x = rng.uniform(-0.5, 0.5, size=robot.nx) * robot.velocity_limits
    x[0] = 0.6 * robot.velocity_limits[0]  # drive forward
    x[1] = 0.8  # steer while driving: Sdot x is large
    xdot = rng.uniform(-0.5, 0.5, size=robot.nx)
    return q, x, xdot


def rolling_path(robot, q0, x0, xdot, times, substeps=200):
    """Configurations at ``times`` (sorted, containing 0) of the motion q' = S(q) (x0 + t xdot)
    from q(0) = q0, integrated by the explicit midpoint rule on the configuration manifold."""
    model = robot.model

    def flow(q, t0, t1):
        h = (t1 - t0) / substeps
        for k in range(substeps):
            t = t0 + k * h
            mid = pin.integrate(model, q, 0.5 * h * robot.null_space(q) @ (x0 + t * xdot))
            q = pin.integrate(model, q, h * robot.null_space(mid) @ (x0 + (t + 0.5 * h) * xdot))
        return q

    out = {}
    for direction in (1.0, -1.0):
        q, t_prev = q0.copy(), 0.0
        for t in sorted((t for t in times if direction * t > 0), key=abs):
            q = flow(q, t_prev, t)
            out[t], t_prev = q, t
    out[0.0] = q0.copy()
    return np.array([out[t] for t in times])


def _tool(robot, q):
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return robot.data.oMf[robot.frame_id("tool_link")].translation.copy()


def test_the_rolling_path_rolls(tricycle, rng):
    """The reference path itself: its tangent displacements are S x (no slip) to the integrator's order."""
    q, x, xdot = _state(tricycle, rng)
    e = 1e-3
    qs = rolling_path(tricycle, q, x, xdot, [-e, 0.0, e])
    v = (pin.difference(tricycle.model, qs[0], qs[2])) / (2 * e)
    np.testing.assert_allclose(v, tricycle.null_space(q) @ x, atol=1e-5)


def test_hand_acceleration_on_a_rolling_path(tricycle, rng):
    """J_u xdot + d/dt(J_u) x equals the second central difference of the hand's position along
    the rolling path; d/dt(J_u) x holds J Sdot x (without it the error is ~|J Sdot x|)."""
    for _ in range(3):
        q, x, xdot = _state(tricycle, rng)
        terms = motion_terms(tricycle, q, x, "translational")
        e = 2e-3
        qs = rolling_path(tricycle, q, x, xdot, [-e, 0.0, e])
        p = [_tool(tricycle, qq) for qq in qs]
        fd = (p[0] - 2 * p[1] + p[2]) / e**2
        accel = terms.J_u @ xdot + terms.drift
        np.testing.assert_allclose(accel, fd, atol=1e-4 * max(1.0, np.abs(fd).max()))
        # the Sdot x share is far above the tolerance: this test sees it missing
        J = frame_jacobians(tricycle, q, "translational")
        sdot_share = J @ tricycle.null_space_rate(q, x) @ x
        assert np.linalg.norm(sdot_share) > 100 * 1e-4 * max(1.0, np.abs(fd).max())


def test_in_motion_efforts_against_rnea_with_sdot(tricycle, rng):
    """MotionTerms.torques and the in-motion ellipsoid's form equal S^T RNEA(q, S x, S xdot + Sdot x)
    plus the hand's share of the object's wrench, for the paper's policy xdot."""
    for _ in range(3):
        q, x, _ = _state(tricycle, rng)
        terms = motion_terms(tricycle, q, x, "translational")
        a_o = rng.normal(size=3)
        xdot = terms.joint_accelerations(a_o)
        S, Sdot = terms.S, tricycle.null_space_rate(q, x)
        tau = S.T @ pin.rnea(tricycle.model, tricycle.model.createData(), q, S @ x, S @ xdot + Sdot @ x)
        h = np.linalg.pinv(terms.W) @ (terms.M_o @ a_o + terms.c_o + terms.g_o)
        expected = np.linalg.solve(terms.Q, tau + terms.J_u.T @ h)
        scale = np.abs(expected).max()
        np.testing.assert_allclose(terms.torques(xdot, a_o), expected, atol=1e-8 * scale)
        Jp, Wp = np.linalg.pinv(terms.J_u), np.linalg.pinv(terms.W)
        Lam = np.linalg.solve(terms.Q, terms.P @ Jp @ terms.W.T + terms.J_u.T @ Wp @ terms.M_o)
        mu = np.linalg.solve(terms.Q, -terms.xi_effective + terms.J_u.T @ Wp @ (terms.g_o + terms.c_o))
        np.testing.assert_allclose(Lam @ a_o + mu, expected, atol=1e-8 * scale)
        # the policy's xdot gives the hand the acceleration a_o (the drift, Sdot x in it, included)
        np.testing.assert_allclose(terms.object_acceleration(xdot), a_o, atol=1e-8)
        without = S.T @ pin.rnea(tricycle.model, tricycle.model.createData(), q, S @ x, S @ xdot)
        assert np.abs(without - tau).max() > 1e-3 * scale  # Sdot x is really in the reference


def test_trajectory_estimates_on_a_rolling_path(tricycle, rng):
    """trajectory_from_samples on configurations sampled along a rolling path of constant
    reduced acceleration: x and xdot come back (xdot = S^+ (a - Sdot x)), without slip."""
    q, x, xdot = _state(tricycle, rng)
    h = 0.01
    times = h * np.arange(-3, 4)
    qs = rolling_path(tricycle, q, x, xdot, list(times), substeps=50)
    traj = trajectory_from_samples(tricycle, times, qs)
    for i in range(1, len(times) - 1):
        np.testing.assert_allclose(traj.x[i], x + times[i] * xdot, atol=1e-3)
        np.testing.assert_allclose(traj.xdot[i], xdot, atol=2e-2)
        assert traj.slip[i] < 1e-4
    # what dropping Sdot x would cost is far above the tolerance
    middle = 3
    S_pinv = np.linalg.pinv(tricycle.null_space(qs[middle]))
    share = S_pinv @ tricycle.null_space_rate(qs[middle], traj.x[middle]) @ traj.x[middle]
    assert np.abs(share).max() > 0.5


def test_path_terms_keep_sdot_on_a_rolling_path(tricycle, rng):
    """retime's stacked rows (path_terms) against motion_terms where Sdot x_s is not zero: the
    path's samples on the rolling path, x_s = x(t) and x_ss = xdot."""
    from test_retime import assert_path_terms_match

    q, x, xdot = _state(tricycle, rng)
    times = np.linspace(-0.1, 0.1, 5)
    qs = rolling_path(tricycle, q, x, xdot, times, substeps=20)
    path = trajectory_from_samples(tricycle, times, qs, x + times[:, None] * xdot, np.tile(xdot, (5, 1)))
    turning = tricycle.null_space_rate(qs[2], path.x[2]) @ path.x[2]
    assert np.abs(turning).max() > 0.1  # the term under test is there
    assert_path_terms_match(tricycle, path, "spatial", 1.5)
