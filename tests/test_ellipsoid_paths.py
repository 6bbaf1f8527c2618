"""The ellipsoids' fast (Gram-matrix) paths agree with the exact SVD paths they shortcut.

Both paths compute the same sets; the fast one is taken only while the Gram matrices are
well-conditioned (condition number below 1e8), where squaring costs at most ~1e-8 relative
accuracy in the worst case; here the configurations are generic, so 1e-9 relative holds.
"""

from __future__ import annotations

import numpy as np
import pytest

from mobmanip.analysis import analyze
from mobmanip.sets import ellipsoid as ellipsoids
from mobmanip.sets.ellipsoid import Ellipsoid


def _assert_same(fast, exact, rtol=1e-9):
    assert fast.empty == exact.empty and fast.degenerate == exact.degenerate
    scale = max(float(exact.semi_axes[0]), 1e-300)
    np.testing.assert_allclose(fast.semi_axes, exact.semi_axes, rtol=rtol, atol=rtol * scale)
    np.testing.assert_allclose(fast.center, exact.center, rtol=rtol, atol=rtol * scale)
    if not exact.empty:
        np.testing.assert_allclose(fast.generator @ fast.generator.T, exact.generator @ exact.generator.T,
                                   rtol=rtol, atol=rtol * scale**2)  # fmt: skip
        np.testing.assert_allclose(fast.matrix, exact.matrix, rtol=1e-7, atol=1e-9 * np.abs(exact.matrix).max())


def _random_q(robot, rng):
    joints = {name: rng.uniform(-np.pi, np.pi) for arm in robot.arms for name in arm.joint_names}
    return robot.configuration((rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-np.pi, np.pi)), joints)


@pytest.fixture
def general_branch_calls(monkeypatch):
    """Count the calls of Ellipsoid.from_generator: for a non-empty ellipsoid only the general
    (null-space) branches of mobmanip.sets.ellipsoid call it; the full-rank branches build the
    Ellipsoid directly. So the count tells which branch ran."""
    calls = []
    original = Ellipsoid.from_generator.__func__

    def spy(cls, *args, **kwargs):
        calls.append(args)
        return original(cls, *args, **kwargs)

    monkeypatch.setattr(Ellipsoid, "from_generator", classmethod(spy))
    return calls


@pytest.mark.parametrize("task", ["planar", "planar_rigid"])
def test_fast_and_exact_paths_agree_on_random_configurations(robot, task, monkeypatch, general_branch_calls):
    """The reference path's full-rank branches against its general branches, both reached
    through analyze(method="exact") (the compiled kernel is never involved)."""
    rng = np.random.default_rng(7)
    configurations = [_random_q(robot, rng) for _ in range(20)]
    fast = []
    for k, q in enumerate(configurations):
        general_branch_calls.clear()
        fast.append(analyze(robot, q, task, decoupled=bool(k % 2), method="exact"))
        assert not general_branch_calls  # both ellipsoids from the full-rank branches
    monkeypatch.setattr(ellipsoids, "FAST_RTOL", np.inf)  # every call takes the general branches
    for k, (q, quick) in enumerate(zip(configurations, fast)):
        general_branch_calls.clear()
        exact = analyze(robot, q, task, decoupled=bool(k % 2), method="exact")
        assert len(general_branch_calls) == 2  # kinematic and dynamic
        assert not quick.dynamic.empty
        _assert_same(quick.kinematic, exact.kinematic)
        _assert_same(quick.dynamic, exact.dynamic)


@pytest.mark.parametrize("load", [0.3, 0.9, 1.5])
def test_shifted_and_empty_dynamic_ellipsoids_agree(robot, load, monkeypatch, general_branch_calls):
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
    assert len(general_branch_calls) == int(quick.empty)  # the full-rank branch builds a non-empty set itself
    monkeypatch.setattr(ellipsoids, "FAST_RTOL", np.inf)
    general_branch_calls.clear()
    exact = ellipsoids.dynamic_ellipsoid(J, W, P, Q, xi, M_o, g_o, limits)
    assert general_branch_calls  # the general branch ran
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
