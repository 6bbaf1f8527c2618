"""The compiled kernel (mobmanip.engine.kernel) against the exact SVD paths and against NumPy."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import random_configurations
from mobmanip.analysis import analyze
from mobmanip.batch import (
    BatchSetup,
    EllipsoidBatch,
    Workspace,
    analyze_batch,
    ellipsoids_from_terms,
    iter_terms,
    kernel_available,
    pinocchio_pass,
)
from mobmanip.engine.setup import mass_matrix_pattern
from mobmanip.terms.grasp import HeldObject
from test_batch import assert_same_ellipsoid

pytestmark = pytest.mark.skipif(not kernel_available(), reason="Numba is not installed")


def assert_same_analysis(fast, exact, label):
    for name in ("unified_jacobian", "reduced_inertia", "reduced_inertia_decoupled", "bias", "grasp_matrix"):
        a, b = getattr(fast, name), getattr(exact, name)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * max(1.0, np.abs(b).max()), err_msg=f"{label} {name}")
    np.testing.assert_allclose(fast.end_effector_positions, exact.end_effector_positions, atol=1e-14)
    assert_same_ellipsoid(fast.kinematic, exact.kinematic, f"{label} kinematic")
    assert_same_ellipsoid(fast.dynamic, exact.dynamic, f"{label} dynamic")


@pytest.mark.parametrize(
    ("name", "task", "platform"),
    [
        ("planar_dual_arm", "planar", "own"),
        ("planar_dual_arm", "planar_rigid", "own"),
        ("planar_dual_arm_omni", "planar_rigid", "own"),
        ("tiago_dual", "spatial", "own"),
        ("tiago_dual", "spatial", "fixed"),
        ("tiago_dual_torso", "translational", "own"),
        ("ur5", "spatial", "own"),
    ],
)
def test_single_configuration_equals_exact_path(name, task, platform, rng):
    """analyze's compiled path equals the SVD-based reference (analyze(method="exact"))."""
    robot = mobmanip.load_robot(name)
    robot = robot if platform == "own" else robot.with_platform("fixed")
    for i, q in enumerate(random_configurations(robot, rng, 12)):
        for decoupled in (False, True):
            fast = analyze(robot, q, task, decoupled=decoupled)
            exact = analyze(robot, q, task, decoupled=decoupled, method="exact")
            assert_same_analysis(fast, exact, f"{name} {task} row {i} decoupled={decoupled}")


def test_explicit_object_with_full_inertia(tiago, rng):
    """An object given explicitly (offsets not at the centroid, a non-diagonal inertia) goes
    through the kernel's explicit-object inputs and matches the exact path."""
    A = rng.standard_normal((3, 3))
    inertia = 0.05 * (A @ A.T + np.eye(3))
    for q in random_configurations(tiago, rng, 8):
        pin.framesForwardKinematics(tiago.model, tiago.data, q)
        points = np.array([tiago.data.oMf[arm.frame_id].translation for arm in tiago.arms])
        obj = HeldObject(2.5, inertia, points.mean(axis=0) + [0.02, -0.01, 0.03], points - points.mean(axis=0))
        fast = analyze(tiago, q, "spatial", held_object=obj)
        exact = analyze(tiago, q, "spatial", held_object=obj, method="exact")
        assert fast.held_object is obj
        assert_same_analysis(fast, exact, "explicit object")


def test_input_matrix_not_identity_is_applied(tiago, rng):
    """Q = S^T B is the identity for every built-in robot; give the setup another invertible Q
    (as a transmission would) and check the kernel's Q^-1 branch against the NumPy and SVD
    paths, which apply it independently."""
    setup = BatchSetup(tiago, "spatial")
    Q = np.eye(setup.nx) + 0.1 * rng.standard_normal((setup.nx, setup.nx))
    setup.Q_inv = np.linalg.inv(Q)
    setup.Q_inv_kernel = np.ascontiguousarray(setup.Q_inv)
    qs = np.array(random_configurations(tiago, rng, 40))
    results = {}
    for method in ("auto", "numpy", "svd"):
        dyn = EllipsoidBatch.allocate(len(qs), setup.m)
        for start, t in iter_terms(setup, qs):
            ellipsoids_from_terms(setup, t, dynamic=dyn, offset=start, method=method)
        results[method] = dyn
    plain = analyze_batch(tiago, qs, "spatial")
    for i in range(len(qs)):
        assert_same_ellipsoid(results["auto"][i], results["svd"][i], f"auto row {i}")
        assert_same_ellipsoid(results["numpy"][i], results["svd"][i], f"numpy row {i}")
        assert not np.allclose(results["auto"].semi_axes[i], plain.dynamic.semi_axes[i])


def test_kernel_numpy_and_svd_paths_agree_on_many_rows(tiago):
    """Three independent implementations over 2,000 random TIAGo++ configurations, with a heavy
    object so that some dynamic ellipsoids are empty."""
    rng = np.random.default_rng(11)
    qs = np.array(random_configurations(tiago, rng, 2000))
    results = {m: analyze_batch(tiago, qs, "spatial", object_mass=25.0, method=m) for m in ("auto", "numpy", "svd")}
    reference = results["svd"]
    assert 0 < reference.dynamic.empty.sum() < len(qs)
    for method in ("auto", "numpy"):
        for name in ("kinematic", "dynamic"):
            got, ref = getattr(results[method], name), getattr(reference, name)
            np.testing.assert_array_equal(got.empty, ref.empty)
            np.testing.assert_array_equal(got.degenerate, ref.degenerate)
            scale = np.maximum(ref.semi_axes[:, 0], np.linalg.norm(ref.center, axis=1))[:, None]
            assert np.all(np.abs(got.semi_axes - ref.semi_axes) <= 1e-10 * scale), (method, name)
            assert np.all(np.abs(got.center - ref.center) <= 1e-10 * scale), (method, name)
    # the kernel certifies nearly every row; the rest went to the SVD path
    assert results["auto"].svd_path.mean() < 0.01


def test_singular_rows_are_not_certified(robot):
    """Stretched arms on a locked platform: the kinematic ellipsoid is degenerate, which the
    closed forms cannot represent; the kernel must hand the row to the SVD path."""
    fixed = robot.with_platform("fixed")
    joints = {}
    for arm in fixed.arms:
        joints.update(zip(arm.joint_names, (0.3, 0.0, 0.0)))
    q = fixed.configuration((0.4, -0.1, 0.2), joints)
    batch = analyze_batch(fixed, q[None, :], "planar")
    assert batch.svd_path[0] and batch.kinematic.degenerate[0]
    single = analyze(fixed, q, "planar")
    assert single.kinematic.degenerate and single.kinematic.semi_axes[-1] == 0.0


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual_torso", "ur5"])
@pytest.mark.parametrize("bindings", ["conventions", "no conventions"])
def test_probed_pass_gives_what_separate_pinocchio_calls_give(name, bindings, rng):
    """One CRBA call per configuration on the probed model: its world joint Jacobians, M, the
    gravity probe's row and the frame probes' columns equal computeJointJacobians, crba,
    computeGeneralizedGravity and the frame placements of the robot's own model. The same
    where the bindings know no conventions (Jacobians then come from their own call)."""
    robot = mobmanip.load_robot(name)
    setup = BatchSetup(robot)
    probed = setup.probed
    assert probed.model.nv == robot.model.nv + 1 + 2 * len(robot.arms)
    qs = np.array(random_configurations(robot, rng, 5))
    ws = Workspace(probed, len(qs))
    if bindings == "no conventions":
        pinocchio_pass(probed, qs, ws, convention=None)
    else:
        pinocchio_pass(probed, qs, ws)
    Jw, M, g = probed.robot_jacobians(ws.Ja), probed.robot_mass_matrices(ws.Ma), probed.gravity_torques(ws.Ma)
    positions = probed.frame_positions(ws.Ja)
    weight = np.linalg.norm(robot.model.gravity.linear) * sum(inertia.mass for inertia in robot.model.inertias)
    data = robot.model.createData()
    for i, q in enumerate(qs):
        np.testing.assert_allclose(Jw[i], pin.computeJointJacobians(robot.model, data, q), rtol=0, atol=1e-13)
        pin.framesForwardKinematics(robot.model, data, q)
        for a, arm in enumerate(robot.arms):
            np.testing.assert_allclose(positions[i, a], data.oMf[arm.frame_id].translation, rtol=0, atol=1e-14)
        Mq = pin.crba(robot.model, data, q)
        np.testing.assert_allclose(np.triu(M[i]), np.triu(Mq), rtol=0, atol=1e-12 * np.abs(Mq).max())
        gq = pin.computeGeneralizedGravity(robot.model, data, q)  # ~0 for a planar robot: scale by weight x 1 m
        np.testing.assert_allclose(g[i], gq, rtol=0, atol=1e-13 * weight)
    # the probes are massless: they add nothing to the robot's M
    probes = np.setdiff1d(np.arange(probed.model.nv), probed.vmap.astype(int))
    assert len(probes) == 1 + 2 * len(robot.arms)
    assert np.all(np.triu(ws.Ma)[:, probes[1:], :] == 0.0)


def test_probes_follow_any_gravity(rng):
    """The gravity probe points against the model's gravity, whatever its direction and size."""
    robot = mobmanip.load_robot("tiago_dual")
    robot.model.gravity.linear = np.array([1.5, -2.0, -4.0])
    setup = BatchSetup(robot)
    qs = np.array(random_configurations(robot, rng, 3))
    ws = Workspace(setup.probed, len(qs))
    pinocchio_pass(setup.probed, qs, ws)
    g = setup.probed.gravity_torques(ws.Ma)
    data = robot.model.createData()
    for i, q in enumerate(qs):
        gq = pin.computeGeneralizedGravity(robot.model, data, q)
        np.testing.assert_allclose(g[i], gq, rtol=0, atol=1e-12 * np.abs(gq).max())


@pytest.mark.parametrize("name", ["tiago_dual_torso", "planar_dual_arm_omni"])
def test_sparsity_the_kernel_skips_is_structural(name, rng):
    """M is zero outside the ancestor pattern at random configurations (CRBA, both triangles),
    so P = S^T M S is zero outside the plan's entries; and J_u is zero outside each arm's
    columns, so two arms' rows meet only on the columns both can use."""
    robot = mobmanip.load_robot(name)
    setup = BatchSetup(robot)
    pattern = mass_matrix_pattern(robot.model)
    assert not pattern.all()  # the arms are separate branches: their coupling is skipped
    ptr, rows, cols = setup.P_plan[:3]
    listed = np.zeros((setup.nx, setup.nx), dtype=bool)
    listed[rows.astype(int), cols.astype(int)] = listed[cols.astype(int), rows.astype(int)] = True
    zptr, zidx = setup.P_plan[-2:]
    for j in range(setup.nx):
        np.testing.assert_array_equal(np.sort(zidx[zptr[j] : zptr[j + 1]]), np.flatnonzero(listed[j]))
    for q in random_configurations(robot, rng, 5):
        M = pin.crba(robot.model, robot.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert np.all(M[~pattern] == 0.0)
        P = robot.S.T @ M @ robot.S
        assert np.all(P[~listed] == 0.0)
        J_u = analyze(robot, q, method="exact").unified_jacobian
        m = J_u.shape[0] // setup.k
        for a in range(setup.k):
            outside = np.ones(setup.nx, dtype=bool)
            outside[setup.arm_cols[a, : setup.n_arm_cols[a]].astype(int)] = False
            assert np.all(J_u[a * m : (a + 1) * m, outside] == 0.0)
            for b in range(setup.k):
                both = setup.pair_cols[a, b, : setup.n_pair_cols[a, b]].astype(int)
                expected = np.flatnonzero(~outside & np.any(J_u[b * m : (b + 1) * m] != 0.0, axis=0))
                assert set(expected) <= set(both)


# ----------------------------------------------------------------------------------------------
# the symmetric eigensolver


def _eigh(A):
    from mobmanip.engine.kernel import eigh

    n = A.shape[0]
    V = np.array(A, dtype=float, copy=True)
    d, e = np.zeros(n), np.zeros(n)
    converged = eigh(V, d, e, n)
    return converged, d, V


@pytest.mark.parametrize("n", [1, 2, 3, 6, 9])
def test_eigh_matches_lapack_and_is_orthogonal(n):
    rng = np.random.default_rng(n)
    cases = []
    for _ in range(200):
        A = rng.standard_normal((n, n))
        cases.append(A + A.T)
    G = rng.standard_normal((n, max(n - 2, 1)))
    cases.append(G @ G.T)  # rank-deficient
    cases.append(np.diag(np.repeat([2.0, 1.0], n)[:n]))  # repeated eigenvalues
    cases.append(1e-200 * np.eye(n) + 1e-210)  # tiny entries: pre-scaling avoids underflow
    cases.append(1e200 * (cases[0] / np.abs(cases[0]).max()))  # huge entries: no overflow
    cases.append(np.zeros((n, n)))
    for A in cases:
        converged, d, V = _eigh(A)
        assert converged
        ref = np.linalg.eigvalsh(A)
        size = max(np.abs(ref).max(), np.finfo(float).tiny)
        assert np.all(np.diff(d) >= 0.0)
        np.testing.assert_allclose(d, ref, rtol=0, atol=20 * n * np.finfo(float).eps * size)
        np.testing.assert_allclose(V.T @ V, np.eye(n), atol=20 * n * np.finfo(float).eps)
        np.testing.assert_allclose((V * d) @ V.T, A, rtol=0, atol=20 * n * np.finfo(float).eps * size)


def test_eigh_reports_nan_input():
    A = np.eye(4)
    A[1, 2] = A[2, 1] = np.nan
    converged, _, _ = _eigh(A)
    assert not converged


def test_eigh_pair_is_two_independent_solves():
    """Solved in lockstep, each problem gets exactly what it gets alone, whatever the other does:
    a different size of spectrum, zero, NaN, or not wanted."""
    from mobmanip.engine.kernel import eigh_pair

    rng = np.random.default_rng(7)
    n = 6
    G = rng.standard_normal((n, 3))
    others = [rng.standard_normal((n, n)) for _ in range(3)] + [G @ G.T, np.zeros((n, n)), np.full((n, n), np.nan)]
    for _ in range(30):
        A = rng.standard_normal((n, n))
        A = A + A.T
        alone_ok, d_alone, V_alone = _eigh(A)
        for other in others:
            B = other + other.T
            V1, V2 = A.copy(), B.copy()
            d1, e1, d2, e2 = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
            ok1, ok2 = eigh_pair(V1, d1, e1, V2, d2, e2, n, True, True)
            assert ok1 == alone_ok
            np.testing.assert_array_equal(d1, d_alone)
            np.testing.assert_array_equal(V1, V_alone)
            other_ok, d_other, V_other = _eigh(B)
            assert ok2 == other_ok
            np.testing.assert_array_equal(d2, d_other)
            if other_ok:
                np.testing.assert_array_equal(V2, V_other)
        # the second problem not wanted: left untouched, reported converged
        V2 = np.full((n, n), 3.0)
        ok1, ok2 = eigh_pair(A.copy(), np.zeros(n), np.zeros(n), V2, np.zeros(n), np.zeros(n), n, True, False)
        assert ok1 == alone_ok and ok2 and np.all(V2 == 3.0)
