"""Capacity in motion (mobmanip.motion): velocity terms against Pinocchio and finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from mobmanip.analysis import analyze
from mobmanip.errors import ConfigurationError, MobmanipError
from mobmanip.motion import analyze_motion, motion_terms
from mobmanip.terms.dynamics import frame_jacobians
from mobmanip.terms.grasp import HeldObject


def _moving_state(robot, rng, scale=0.5):
    q = robot.hold_configuration()
    q = pin.integrate(robot.model, q, robot.null_space(q) @ rng.normal(scale=0.3, size=robot.nx))
    x = scale * rng.uniform(-1, 1, size=robot.nx) * robot.velocity_limits
    return q, x


def _same_ellipsoid(a, b, rtol=1e-9):
    scale = max(float(np.max(a.semi_axes)), 1.0)
    assert a.empty == b.empty
    np.testing.assert_allclose(a.center, b.center, atol=rtol * scale)
    np.testing.assert_allclose(a.semi_axes, b.semi_axes, atol=rtol * scale)
    np.testing.assert_allclose(a.generator @ a.generator.T, b.generator @ b.generator.T, atol=rtol * scale**2)


@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_at_rest_equals_analyze_paper_robot(robot, rng, task):
    q, _ = _moving_state(robot, rng)
    moving = analyze_motion(robot, q, np.zeros(robot.nx), task)
    rest = analyze(robot, q, task, method="exact")
    _same_ellipsoid(moving.dynamic, rest.dynamic)
    _same_ellipsoid(moving.kinematic, rest.kinematic)


@pytest.mark.parametrize("task", ["spatial", "translational"])
def test_at_rest_equals_analyze_tiago(tiago, rng, task):
    q, _ = _moving_state(tiago, rng)
    for decoupled in (False, True):
        moving = analyze_motion(tiago, q, np.zeros(tiago.nx), task, decoupled=decoupled)
        rest = analyze(tiago, q, task, method="exact", decoupled=decoupled)
        _same_ellipsoid(moving.dynamic, rest.dynamic)


def _hand_velocities(robot, q, x, task):
    return frame_jacobians(robot, q, task) @ robot.null_space(q) @ x


def _default_W(robot, q, task):
    return analyze(robot, q, task, method="exact").grasp_matrix


@pytest.mark.parametrize("task", ["spatial", "planar_rigid"])
def test_hand_drift_and_grasp_rate_are_derivatives_along_the_motion(tiago, rng, task):
    """d/dt(J_u) x and dW/dt equal central differences of J_u and W along q(t) = q (+) t S x."""
    q, x = _moving_state(tiago, rng)
    terms = motion_terms(tiago, q, x, task)
    v = tiago.null_space(q) @ x
    e = 1e-6
    qp, qm = pin.integrate(tiago.model, q, e * v), pin.integrate(tiago.model, q, -e * v)
    Jp = frame_jacobians(tiago, qp, task) @ tiago.null_space(qp)
    Jm = frame_jacobians(tiago, qm, task) @ tiago.null_space(qm)
    fd_drift = (Jp - Jm) @ x / (2 * e)
    np.testing.assert_allclose(terms.drift, fd_drift, atol=1e-6 * max(1.0, np.abs(fd_drift).max()))
    fd_W = (_default_W(tiago, qp, task) - _default_W(tiago, qm, task)) / (2 * e)
    np.testing.assert_allclose(terms.W_rate, fd_W, atol=1e-6)
    assert np.abs(terms.W_rate).max() > 1e-3  # the hands do move relative to each other


def test_torques_equal_rnea(tiago, rng):
    """Lambda_o a_o + mu_o(q, x) (via the in-motion ellipsoid's terms) equals S^T RNEA at
    (q, S x, S xdot) plus the hands' share of the object's wrench, for the policy's xdot."""
    for task in ("spatial", "translational"):
        q, x = _moving_state(tiago, rng)
        terms = motion_terms(tiago, q, x, task)
        a_o = rng.normal(size=terms.task.dim)
        xdot = terms.joint_accelerations(a_o)
        S = terms.S
        a = S @ xdot + tiago.null_space_rate(q, x) @ x  # the joint accelerations, Sdot x included
        tau_rnea = S.T @ pin.rnea(tiago.model, tiago.model.createData(), q, S @ x, a)
        h = np.linalg.pinv(terms.W) @ (terms.M_o @ a_o + terms.c_o + terms.g_o)
        expected = np.linalg.solve(terms.Q, tau_rnea + terms.J_u.T @ h)
        # the same torques from the in-motion ellipsoid's form: Q^-1 (P J^+ W^T + J^T W^+ M_o) a_o + mu_o
        Jp, Wp = np.linalg.pinv(terms.J_u), np.linalg.pinv(terms.W)
        Lam = np.linalg.solve(terms.Q, terms.P @ Jp @ terms.W.T + terms.J_u.T @ Wp @ terms.M_o)
        mu = np.linalg.solve(terms.Q, -terms.xi_effective + terms.J_u.T @ Wp @ (terms.g_o + terms.c_o))
        np.testing.assert_allclose(Lam @ a_o + mu, expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())
        np.testing.assert_allclose(terms.torques(xdot, a_o), expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())
        # the policy's xdot gives the hands W^T a_o + Wdot^T v_o: object acceleration a_o comes back
        np.testing.assert_allclose(terms.object_acceleration(xdot), a_o, atol=1e-8)


def test_in_motion_ellipsoid_boundary_saturates_torques(tiago, rng):
    """Points on the in-motion dynamic ellipsoid need torques of normalized norm exactly 1 (RNEA)."""
    q, x = _moving_state(tiago, rng, scale=0.8)
    task = "translational"
    ma = analyze_motion(tiago, q, x, task)
    rest = analyze(tiago, q, task, method="exact").dynamic
    assert not np.allclose(ma.dynamic.center, rest.center, atol=1e-6)  # the velocity terms matter
    terms = ma.terms
    S = terms.S
    for _ in range(5):
        u = rng.normal(size=3)
        a_o = ma.dynamic.center + ma.dynamic.generator @ (u / np.linalg.norm(u))
        xdot = terms.joint_accelerations(a_o)
        a = S @ xdot + tiago.null_space_rate(q, x) @ x
        tau = S.T @ pin.rnea(tiago.model, tiago.model.createData(), q, S @ x, a)
        tau = np.linalg.solve(terms.Q, tau + terms.J_u.T @ np.linalg.pinv(terms.W) @ (terms.M_o @ a_o + terms.g_o))
        assert np.linalg.norm(tau / terms.effort_limits) == pytest.approx(1.0, abs=1e-8)


def test_object_gyroscopic_wrench_matches_pinocchio(tiago, rng):
    """c_o = [0; w x I w] is Pinocchio's v x* (I v) of the object's spatial inertia at its centre."""
    q, x = _moving_state(tiago, rng)
    inertia = np.diag([0.02, 0.05, 0.08])
    positions = analyze(tiago, q, "spatial", method="exact").end_effector_positions
    obj = HeldObject.between(positions, 1.5, inertia)
    terms = motion_terms(tiago, q, x, "spatial", held_object=obj)
    omega = terms.v_o[3:]
    body = pin.Inertia(1.5, np.zeros(3), inertia)
    expected = body.vxiv(pin.Motion(np.zeros(3), omega)).vector
    np.testing.assert_allclose(terms.c_o, expected, atol=1e-12)
    assert np.linalg.norm(omega) > 1e-3


def test_planar_task_velocity_terms_paper_robot(robot, rng):
    """The paper's robot at speed: bias equals S^T nonLinearEffects, and the ellipsoid moves."""
    q, x = _moving_state(robot, rng, scale=0.9)
    terms = motion_terms(robot, q, x, "planar")
    S = terms.S
    rnea0 = pin.rnea(robot.model, robot.model.createData(), q, S @ x, np.zeros(robot.model.nv))
    np.testing.assert_allclose(terms.xi, -S.T @ rnea0, atol=1e-10)
    np.testing.assert_allclose(terms.W_rate, 0.0)  # W = [I I] is constant in the planar task
    # that zero is not the code's answer to every input: with the object's yaw in the task, the
    # same motion turns the grasp and W_rate equals the central difference of W along the motion
    v = S @ x
    e = 1e-6
    qp, qm = pin.integrate(robot.model, q, e * v), pin.integrate(robot.model, q, -e * v)
    for task, moving in (("planar", False), ("planar_rigid", True)):
        rate = motion_terms(robot, q, x, task).W_rate
        fd = (_default_W(robot, qp, task) - _default_W(robot, qm, task)) / (2 * e)
        np.testing.assert_allclose(rate, fd, atol=1e-6)
        assert (np.abs(fd).max() > 1e-2) == moving
        # and the hands' drift is the derivative of J_u along the motion in both tasks
        Jp = frame_jacobians(robot, qp, task) @ robot.null_space(qp)
        Jm = frame_jacobians(robot, qm, task) @ robot.null_space(qm)
        fd_drift = (Jp - Jm) @ x / (2 * e)
        np.testing.assert_allclose(
            motion_terms(robot, q, x, task).drift, fd_drift, atol=1e-6 * max(1, np.abs(fd_drift).max())
        )


def test_bad_velocity_is_refused(robot):
    q = robot.neutral()
    with pytest.raises(ConfigurationError, match="shape"):
        motion_terms(robot, q, np.zeros(robot.nx + 1))
    x = np.zeros(robot.nx)
    x[3] = np.nan
    with pytest.raises(MobmanipError, match=robot.reduced_velocity_names[3]):
        motion_terms(robot, q, x)
