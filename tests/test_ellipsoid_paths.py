"""The ellipsoids' fast (Gram-matrix) paths agree with the exact SVD paths they shortcut.

Both paths compute the same sets; the fast one is taken only while the Gram matrices are
well-conditioned (condition number below 1e8), where squaring costs at most ~1e-8 relative
accuracy in the worst case; here the configurations are generic, so 1e-9 relative holds.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from mobmanip import ellipsoids
from mobmanip.analysis import analyze


def _assert_same(fast, exact, rtol=1e-9):
    assert fast.empty == exact.empty and fast.degenerate == exact.degenerate
    scale = max(float(exact.semi_axes[0]), 1e-300)
    np.testing.assert_allclose(fast.semi_axes, exact.semi_axes, rtol=rtol, atol=rtol * scale)
    np.testing.assert_allclose(fast.center, exact.center, rtol=rtol, atol=rtol * scale)
    if not exact.empty:
        np.testing.assert_allclose(fast.generator @ fast.generator.T, exact.generator @ exact.generator.T,
                                   rtol=rtol, atol=rtol * scale**2)  # fmt: skip
        np.testing.assert_allclose(fast.matrix, exact.matrix, rtol=1e-7, atol=1e-9 * np.abs(exact.matrix).max())


@pytest.fixture(scope="module")
def robot():
    return mobmanip.load_robot("planar_dual_arm")


def _random_q(robot, rng):
    joints = {name: rng.uniform(-np.pi, np.pi) for arm in robot.arms for name in arm.joint_names}
    return robot.configuration((rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-np.pi, np.pi)), joints)


@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_fast_and_exact_paths_agree_on_random_configurations(robot, task, monkeypatch):
    rng = np.random.default_rng(7)
    configurations = [_random_q(robot, rng) for _ in range(20)]
    fast = [analyze(robot, q, task, decoupled=bool(k % 2)) for k, q in enumerate(configurations)]
    monkeypatch.setattr(ellipsoids, "_FAST_RTOL", np.inf)  # every call takes the SVD path
    for k, (q, quick) in enumerate(zip(configurations, fast)):
        exact = analyze(robot, q, task, decoupled=bool(k % 2))
        _assert_same(quick.kinematic, exact.kinematic)
        _assert_same(quick.dynamic, exact.dynamic)


@pytest.mark.parametrize("load", [0.3, 0.9, 1.5])
def test_shifted_and_empty_dynamic_ellipsoids_agree(robot, load, monkeypatch):
    """A bias torque of growing size (relative to the limits) shifts, then empties, the set."""
    rng = np.random.default_rng(11)
    q = _random_q(robot, rng)
    result = analyze(robot, q, "planar")
    J, W, P, Q = result.unified_jacobian, result.grasp_matrix, result.reduced_inertia, result.input_matrix
    limits = robot.effort_limits
    xi = rng.normal(size=robot.nx)
    xi *= load / np.linalg.norm(xi / limits)  # ||Z xi|| = load
    M_o, g_o = 2.0 * np.eye(2), np.zeros(2)
    quick = ellipsoids.dynamic_ellipsoid(J, W, P, Q, xi, M_o, g_o, limits)
    monkeypatch.setattr(ellipsoids, "_FAST_RTOL", np.inf)
    exact = ellipsoids.dynamic_ellipsoid(J, W, P, Q, xi, M_o, g_o, limits)
    _assert_same(quick, exact)
    assert np.linalg.norm(exact.center) > 0
    # Independent check of emptiness: least-squares residual of Z(Lambda a + mu) over all a.
    Lam = P @ np.linalg.pinv(J) @ W.T + J.T @ np.linalg.pinv(W) @ M_o
    Z = 1.0 / limits
    mu = -xi
    a_best, *_ = np.linalg.lstsq(Z[:, None] * Lam, -Z * mu, rcond=None)
    residual = np.linalg.norm(Z * (Lam @ a_best + mu))
    assert exact.empty == (residual >= 1.0)
    if load < 1.0:  # the residual never exceeds ||Z mu|| = load, so the set cannot be empty
        assert not exact.empty
    else:  # range(Z Lambda) is 2-D among 8: most of a random bias lies outside it
        assert residual > 1.0 and exact.empty
    np.testing.assert_allclose(exact.center, a_best, rtol=1e-9, atol=1e-12)
