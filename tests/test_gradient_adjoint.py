"""The reverse chain and its tree contractions against independent computations.

- the reverse chain (``GradientEvaluator.batch``) against the forward chain (dC along every
  tangent direction from Pinocchio's kinematic Hessians and dM/dq from the bodies' local
  Hessians): two derivations of the same gradient;
- the closed-form contractions against contractions of Pinocchio's own derivatives (kinematic
  Hessians, RNEA derivatives, gravity derivatives);
- M, g and the bodies' world inertias against Pinocchio's CRBA, RNEA and placements;
- the compiled row loops against the stacked NumPy forms;
- the rank certificate against the SVD test.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import random_configuration
from mobmanip.errors import ModelError
from mobmanip.gradients import INDICES, GradientEvaluator, Objective
from mobmanip.gradients.adjoint import full_rank
from mobmanip.gradients.derivatives import DerivativeWorkspace
from mobmanip.gradients.rank import svd_full_rank
from mobmanip.gradients.tree_adjoint import TreeAdjoint
from mobmanip.robot.tasks import get_task

ROBOTS = ("planar_dual_arm", "tiago_dual", "tiago_dual_torso", "planar_dual_arm_omni", "ur5")


@pytest.fixture(scope="module")
def robots():
    return {name: mobmanip.load_robot(name) for name in ROBOTS}


def _configurations(robot, seed, n):
    rng = np.random.default_rng(seed)
    return np.array([random_configuration(robot, rng) for _ in range(n)])


@pytest.mark.parametrize("name", ROBOTS)
def test_reverse_chain_equals_forward_chain(robots, name):
    """Every objective, kinematic and dynamic (coupled and decoupled), with and without a load:
    the reverse chain's values equal the forward chain's to 1e-9 and its gradients to 1e-6 (the
    bounds test_gradients sets against the reference and differences) on 25 random
    configurations; those within isotropy 1e-3 of a singular posture, where both chains lose
    digits to the conditioning, are left out as in test_gradients."""
    robot = robots[name]
    task = get_task(robot.spec.default_task)
    qs = _configurations(robot, 40 + len(name), 25)
    for mass in (0.0, 3.0):
        at = mobmanip.analyze_batch(robot, qs, object_mass=mass, method="svd")
        for ellipsoid in ("kinematic", "dynamic"):
            s = getattr(at, ellipsoid).semi_axes
            usable = s[:, -1] >= 1e-3 * np.maximum(s[:, 0], 1e-300)
            for index in INDICES:
                direction = tuple(np.eye(task.dim)[-1]) if index == "capacity" else None
                for decoupled in (False, True) if ellipsoid == "dynamic" else (False,):
                    ev = GradientEvaluator(robot, Objective(ellipsoid, index, direction), object_mass=mass,
                                           decoupled=decoupled)  # fmt: skip
                    assert ev.tree is not None
                    value, grad, ok = ev._chunk(qs)
                    ref_value, ref_grad, ref_ok = ev.forward_chunk(qs)
                    np.testing.assert_array_equal(ok, ref_ok)
                    keep = ok & usable
                    np.testing.assert_allclose(value[keep], ref_value[keep], rtol=1e-9, atol=1e-12)
                    assert keep.sum() >= 15
                    error = np.linalg.norm(grad - ref_grad, axis=1)[keep] / np.linalg.norm(ref_grad, axis=1)[keep]
                    assert error.max() < 1e-6, (mass, ellipsoid, index, decoupled, error.max())


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual_torso", "ur5"])
@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_tree_quantities_equal_pinocchio(robots, name, compiled):
    """M, g, the hands' positions and Jacobians, and every body's spatial inertia equal
    Pinocchio's CRBA, generalized gravity, frame placements and Jacobians, and placed inertias."""
    if compiled:
        pytest.importorskip("numba")
    robot = robots[name]
    model, data = robot.model, robot.data
    tree = TreeAdjoint(model, [arm.frame_id for arm in robot.arms], compiled=compiled)
    qs = _configurations(robot, 3, 6)
    t = tree.run(qs)
    I = tree.inertias(t)
    for i, q in enumerate(qs):
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        np.testing.assert_allclose(t.M[i], M, atol=1e-11 * np.abs(M).max())
        np.testing.assert_allclose(t.g[i], pin.computeGeneralizedGravity(model, data, q), atol=1e-10)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for a, arm in enumerate(robot.arms):
            p = data.oMf[arm.frame_id].translation
            np.testing.assert_allclose(t.positions[i, a] + t.reference[i], p, atol=1e-12)
            J = pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(t.frames[i, a], J, atol=1e-12)
        about = pin.SE3(np.eye(3), -t.reference[i])  # world-aligned frame at the reference point
        for j in range(1, model.njoints):
            want = (about * data.oMi[j]).act(model.inertias[j]).matrix()
            np.testing.assert_allclose(I[i, j - 1], want, atol=1e-11 * max(1.0, np.abs(want).max()))


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual_torso"])
@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_contractions_equal_pinocchio_derivatives(robots, name, compiled):
    """sum_r d(a_r^T M b_r)/dq + d(g_bar . g)/dq equals the contraction of RNEA derivatives
    (d(M b)/dq = dtau/dq(q, 0, b) - dg/dq) and gravity derivatives; the frame term equals the
    contraction of Pinocchio's kinematic Hessians and Jacobians."""
    robot = robots[name]
    if compiled:
        pytest.importorskip("numba")
    model, data = robot.model, robot.data
    nv = model.nv
    tree = TreeAdjoint(model, [arm.frame_id for arm in robot.arms], compiled=compiled)
    ws = DerivativeWorkspace(robot, "spatial")
    rng = np.random.default_rng(9)
    qs = _configurations(robot, 11, 4)
    a, b = rng.normal(size=(4, 3, nv)), rng.normal(size=(4, 3, nv))
    g_bar = rng.normal(size=(4, nv))
    J_bar = rng.normal(size=(4, len(robot.arms), 6, nv))
    p_bar = rng.normal(size=(4, len(robot.arms), 3))
    t = tree.run(qs)
    got_m = tree.bilinear_term(t, a, b, g_bar)
    got_f = tree.frame_term(t, J_bar, p_bar)
    zero = np.zeros(nv)
    for i, q in enumerate(qs):
        dg = pin.computeGeneralizedGravityDerivatives(model, data, q).copy()
        want = g_bar[i] @ dg
        for r in range(3):
            dtau, _, _ = pin.computeRNEADerivatives(model, data, q, zero, b[i, r])
            want = want + a[i, r] @ (dtau - dg)
        np.testing.assert_allclose(got_m[i], want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
        d = ws.evaluate(q[None])
        want_f = np.zeros(nv)
        for arm_index in range(len(robot.arms)):
            support = tree.supports[arm_index]
            dJ = d.dJ[0][:, arm_index * 6 : (arm_index + 1) * 6]  # (nv_k, 6, nv)
            want_f += np.einsum("xi,kxi->k", J_bar[i, arm_index] * support, dJ)
            want_f += p_bar[i, arm_index] @ d.J_linear[0, arm_index]
        np.testing.assert_allclose(got_f[i], want_f, rtol=1e-9, atol=1e-9 * np.abs(want_f).max())


def test_rank_certificate_agrees_with_svd():
    """Well-conditioned, nearly singular and exactly singular stacks: the certified test gives
    the SVD test's answer."""
    rng = np.random.default_rng(2)
    A = rng.normal(size=(60, 4, 9))
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    for i, smallest in enumerate(np.logspace(-14, 0, 60)):
        s[i, -1] = smallest * s[i, 0]
    A = (U * s[:, None, :]) @ Vt
    A[0, 2] = A[0, 1]  # exactly singular
    np.testing.assert_array_equal(full_rank(A), svd_full_rank(A))
    np.testing.assert_array_equal(full_rank(np.swapaxes(A, 1, 2)), svd_full_rank(np.swapaxes(A, 1, 2)))


def test_unsupported_joint_takes_the_hessian_path():
    """A model with a spherical joint has no closed forms here: TreeAdjoint refuses it by name."""
    model = pin.buildSampleModelHumanoid()
    with pytest.raises(ModelError, match="no closed-form derivative"):
        TreeAdjoint(model, [model.nframes - 1])
