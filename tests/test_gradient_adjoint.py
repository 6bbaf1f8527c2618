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


def _frame_term_per_hand(tree, t, J_bar, p_bar):
    """The frame term hand after hand (the loop the stacked form replaced), the reference for
    bit-for-bit equality: maps and placements keep their iterates only if the sums do."""

    def cross(u, v):
        c0 = u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1]
        out = np.empty(c0.shape[:1] + (3,) + c0.shape[1:])
        out[:, 0], out[:, 1], out[:, 2] = (
            c0,
            u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0],
        )
        return out

    xi = t.xi
    v, w = xi[:, :3], xi[:, 3:]
    out = np.zeros((xi.shape[0], tree.nv))
    for a in range(tree.k):
        Jb = J_bar[:, a] * tree.supports[a]
        bl, ba = Jb[:, :3], Jb[:, 3:]
        ba = ba + cross(t.positions[:, a, :, None], bl)
        w_bl = cross(w, bl)
        gamma = np.concatenate([w_bl, cross(v, bl) + cross(w, ba)], axis=1)
        G = (gamma.reshape(-1, tree.nv) @ tree.suffix).reshape(gamma.shape)
        out += np.einsum("nxk,nxk->nk", xi, G) * tree.supports[a]
        out += np.einsum("nx,nxk->nk", -w_bl.sum(axis=2) + p_bar[:, a], t.frames[:, a, :3])
    return out


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual"])
def test_frames_and_frame_term_stacked_over_the_hands_equal_the_per_hand_forms_bit_for_bit(robots, name):
    """The pass's frame Jacobians ((v + w x p_a, w) on the columns that move hand a) and the frame
    term are computed for every hand at once; each hand's entries equal the per-hand forms bit
    for bit, in batches of 1 to 5 configurations, so the optimisers' iterates do not change."""
    robot = robots[name]
    tree = TreeAdjoint(robot.model, [arm.frame_id for arm in robot.arms])
    rng = np.random.default_rng(21)
    nv = robot.model.nv
    for n in (1, 3, 5):
        t = tree.run(_configurations(robot, n, n), dynamics=False)
        for a in range(tree.k):
            p = t.positions[:, a]
            wxp = np.stack([t.xi[:, 4] * p[:, 2, None] - t.xi[:, 5] * p[:, 1, None],
                            t.xi[:, 5] * p[:, 0, None] - t.xi[:, 3] * p[:, 2, None],
                            t.xi[:, 3] * p[:, 1, None] - t.xi[:, 4] * p[:, 0, None]], axis=1)  # fmt: skip
            assert np.array_equal(t.frames[:, a, :3], (t.xi[:, :3] + wxp) * tree.supports[a])
            assert np.array_equal(t.frames[:, a, 3:], t.xi[:, 3:] * tree.supports[a])
        J_bar = rng.normal(size=(n, tree.k, 6, nv))
        p_bar = rng.normal(size=(n, tree.k, 3))
        assert np.array_equal(tree.frame_term(t, J_bar, p_bar), _frame_term_per_hand(tree, t, J_bar, p_bar))
        zero = np.zeros((n, tree.k, 3))  # without p_bar: rho alone (adding zeros changes no bit)
        assert np.array_equal(tree.frame_term(t, J_bar), _frame_term_per_hand(tree, t, J_bar, zero))


def test_a_constant_objects_terms_are_the_objects_own_for_every_chunk_size(robots):
    """The chain builds a constant object's W, M_o and g_o once per chunk size: they equal the
    object's (here held between the planar robot's hands, whose planar task sees no offsets),
    stacked, read-only, and follow a change of the object's mass."""
    from mobmanip.terms.grasp import HeldObject

    robot = robots["planar_dual_arm"]
    ev = GradientEvaluator(robot, "dynamic:log_volume", robot.spec.default_task, object_mass=1.5)
    task = ev.task
    for mass in (1.5, 4.0):
        ev.mass = mass
        for n in (1, 4, 1):
            positions = np.random.default_rng(n).normal(size=(n, len(robot.arms), 3))
            W, M_o, g_o, moving = ev._object_terms(positions)
            held = HeldObject.between(positions[0], mass)
            assert not moving and W.shape[0] == n and M_o.shape[0] == n
            assert all(np.array_equal(W[i], held.grasp_matrix(task)) for i in range(n))
            assert all(np.array_equal(M_o[i], held.inertia_matrix(task)) for i in range(n))
            assert np.array_equal(g_o, held.gravity_vector(task))
            assert np.array_equal(M_o[0], mass * np.eye(task.dim))  # mass on every (linear) row
            assert not (W.flags.writeable or M_o.flags.writeable or g_o.flags.writeable)
