"""The engine's certificate, tested from both sides against a 50-digit reference, and the
route without Numba.

The fast paths (compiled kernel, stacked NumPy) accept a row only where an a-priori bound on
their error, relative to the ellipsoid's size, is at most ``FAST_PATH_TOLERANCE``; ``analyze``
promises 1e-9 of the ellipsoid's size. The reference here recomputes each ellipsoid from the
very terms (J_u, P, xi, W) the fast path used, in 50-digit arithmetic, so that what is measured
is the fast path's own rounding error and nothing else.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import mpmath as mp
import numpy as np
import pytest

import mobmanip
from conftest import random_configurations
from mobmanip.analysis import analyze
from mobmanip.batch import analyze_batch, evaluate_one, kernel_available
from mobmanip.errors import ModelError, TaskError
from mobmanip.robot.tasks import get_task
from mobmanip.support import tolerances as tolerances
from mobmanip.terms.grasp import HeldObject

PROMISE = 1e-9  # analyze's docstring: "cannot certify to 1e-9 of its size"
ROOT = Path(__file__).resolve().parents[1]
needs_kernel = pytest.mark.skipif(not kernel_available(), reason="Numba is not installed")


def _mp(A) -> mp.matrix:
    A = np.asarray(A, dtype=float)
    return mp.matrix(A.tolist() if A.ndim == 2 else [[x] for x in A.tolist()])


def reference_ellipsoids(robot, row, task, decoupled):
    """Both ellipsoids from a row's terms in 50 digits, by the closed forms for J of full row
    rank: kinematic A = W (J_hat J_hat^T)^-1 W^T; dynamic L = Z Q^-1 Lambda_o, centre
    -(L^T L)^-1 L^T mu_bar, semi-axes sqrt(rho^2 / eig(L^T L)). Returns ((semi-axes descending,
    centre), (semi-axes descending, centre))."""
    obj = HeldObject.between(row.positions, robot.spec.object_mass)
    with mp.workdps(50):
        J, W = _mp(row.J_u), _mp(row.W)
        J_hat = J * mp.diag([mp.mpf(v) for v in robot.velocity_limits.tolist()])
        kin_eig, _ = mp.eigsy(W * mp.inverse(J_hat * J_hat.T) * W.T)
        kin = sorted((1 / mp.sqrt(x) for x in kin_eig), reverse=True)
        P = _mp(row.P)
        if decoupled:
            e = robot.platform.n_reduced
            for i in range(P.rows):
                for j in range(P.cols):
                    if (i < e) != (j < e):
                        P[i, j] = 0
        J_pinv = J.T * mp.inverse(J * J.T)
        W_pinv = W.T * mp.inverse(W * W.T)
        Q_inv = mp.inverse(_mp(robot.Q))
        Lam = Q_inv * (P * J_pinv * W.T + J.T * W_pinv * _mp(obj.inertia_matrix(task)))
        mu = Q_inv * (-_mp(row.xi) + J.T * W_pinv * _mp(obj.gravity_vector(task)))
        Z = mp.diag([1 / mp.mpf(v) for v in robot.effort_limits.tolist()])
        L, mu_bar = Z * Lam, Z * mu
        H = L.T * L
        center = -(mp.inverse(H) * (L.T * mu_bar))
        residual = L * center + mu_bar
        rho2 = 1 - sum(x**2 for x in residual)
        dyn_eig, _ = mp.eigsy(H)
        dyn = [mp.mpf(0)] * H.rows if rho2 <= 0 else sorted((mp.sqrt(rho2 / x) for x in dyn_eig), reverse=True)
        as_float = lambda values: np.array([float(x) for x in values])  # noqa: E731
        return (as_float(kin), np.zeros(W.rows)), (as_float(dyn), as_float(center))


def relative_error(ellipsoid, reference) -> float:
    """Largest error of the semi-axes and the centre, relative to the ellipsoid's size."""
    semi, center = reference
    scale = max(semi[0], np.linalg.norm(center))
    return max(np.abs(ellipsoid.semi_axes - semi).max(), np.linalg.norm(ellipsoid.center - center)) / scale


def nearly_stretched(robot, bend):
    """The paper's robot with both arms bent by ``bend`` (rad) at the elbow: J_u's condition
    number grows as 1 / bend, up to the stretched (singular) arms at bend = 0."""
    joints = {}
    for arm, sign in zip(robot.arms, (1.0, -1.0)):
        joints.update(zip(arm.joint_names, (0.3 * sign, sign * bend, 0.0)))
    return robot.configuration((0.4, -0.1, 0.2), joints)


def conditioning_family(robot):
    """(robot, q, decoupled) over ten decades of conditioning, moving and locked platform."""
    cases = []
    for platform in ("own", "fixed"):
        r = robot if platform == "own" else robot.with_platform("fixed")
        for bend in np.logspace(-1, -6, 26):
            for decoupled in (False, True):
                cases.append((r, nearly_stretched(r, bend), decoupled))
    return cases


@needs_kernel
def test_kernel_module_holds_no_tolerance_of_its_own():
    """The kernel's only float global is machine epsilon, the tolerance module's own; every
    threshold reaches it as an argument, read from mobmanip.support.tolerances at each call."""
    from mobmanip.engine import kernel

    floats = {name: value for name, value in vars(kernel).items() if isinstance(value, float)}
    assert floats == {"EPS": tolerances.EPS}
    assert kernel.EPS is tolerances.EPS
    assert tolerances.kernel_tolerances()[0] == tolerances.FAST_PATH_TOLERANCE == PROMISE
    assert tolerances.kernel_tolerances()[1:3] == (tolerances.CONDITION_LIMIT, tolerances.GRAM_CONDITION_LIMIT)


@needs_kernel
def test_certificate_threshold_from_both_sides(robot):
    """A row is certified exactly where its error bound is at most the tolerance module's
    threshold; the family reaches both sides of it closely; certified rows keep analyze's
    promise against the 50-digit reference, refused rows go to the SVD path in the batch."""
    threshold = tolerances.FAST_PATH_TOLERANCE
    task = get_task("planar")
    inside = outside = 0
    for r, q, decoupled in conditioning_family(robot):
        row = evaluate_one(r, q, "planar", decoupled=decoupled, method="kernel")
        batch = analyze_batch(r, q[None, :], "planar", decoupled=decoupled)
        certified = row.kinematic is not None or row.dynamic is not None
        reference = reference_ellipsoids(r, row, task, decoupled) if certified else None
        for kind, ellipsoid, bound in (
            ("kinematic", row.kinematic, row.kinematic_bound),
            ("dynamic", row.dynamic, row.dynamic_bound),
        ):
            assert (ellipsoid is not None) == (bound <= threshold), (kind, bound)
            if ellipsoid is not None:
                assert relative_error(ellipsoid, reference[kind == "dynamic"]) <= PROMISE, (kind, bound)
            inside += threshold / 100 <= bound <= threshold
            outside += threshold < bound <= 100 * threshold
        refused = row.kinematic is None or row.dynamic is None
        assert batch.svd_path[0] == refused
    assert inside >= 4 and outside >= 4, (inside, outside)


@needs_kernel
def test_certificate_bound_holds_over_ten_decades(robot, monkeypatch):
    """With the threshold lifted, the kernel answers every row whose closed forms apply: its
    error against the 50-digit reference stays below its a-priori bound, from well-conditioned
    rows to bounds of order one (the bound is what makes the threshold mean something)."""
    monkeypatch.setattr(tolerances, "FAST_PATH_TOLERANCE", 1.0)
    task = get_task("planar")
    bounds = []
    for r, q, decoupled in conditioning_family(robot):
        row = evaluate_one(r, q, "planar", decoupled=decoupled, method="kernel")
        assert (row.kinematic is None) == np.isinf(row.kinematic_bound)
        assert (row.dynamic is None) == np.isinf(row.dynamic_bound)
        if row.kinematic is None and row.dynamic is None:
            continue
        kin_ref, dyn_ref = reference_ellipsoids(r, row, task, decoupled)
        if row.kinematic is not None:
            assert relative_error(row.kinematic, kin_ref) <= row.kinematic_bound
        if row.dynamic is not None:
            assert relative_error(row.dynamic, dyn_ref) <= row.dynamic_bound
            bounds.append(row.dynamic_bound)
    assert min(bounds) < 1e-10 and max(bounds) > 1e-3


def test_numpy_fast_path_keeps_the_promise_near_singularities(robot):
    """The stacked NumPy fast path over the same family: what it certifies is within the
    promise of the 50-digit reference from its own terms, and it certifies well-conditioned
    rows while refusing the nearly singular ones."""
    task = get_task("planar")
    accepted = refused = 0
    for r, q, decoupled in conditioning_family(robot):
        row = evaluate_one(r, q, "planar", decoupled=decoupled, method="numpy")
        assert row.method == "numpy" and row.kinematic_bound is None
        if row.kinematic is None and row.dynamic is None:
            refused += 1
            continue
        kin_ref, dyn_ref = reference_ellipsoids(r, row, task, decoupled)
        for ellipsoid, ref in ((row.kinematic, kin_ref), (row.dynamic, dyn_ref)):
            if ellipsoid is not None:
                accepted += 1
                assert relative_error(ellipsoid, ref) <= PROMISE
            else:
                refused += 1
    assert accepted > 20 and refused > 20


def test_evaluate_one_rejects_bad_requests(robot):
    q = nearly_stretched(robot, 0.5)
    with pytest.raises(TaskError, match="method must be one of"):
        evaluate_one(robot, q, "planar", method="fast")
    with pytest.raises(TaskError, match="one grasp offset per arm"):
        evaluate_one(robot, q, "planar", held_object=HeldObject(1.0, np.eye(3), np.zeros(3), np.zeros((3, 3))))
    if not kernel_available():
        with pytest.raises(ModelError, match="Numba"):
            evaluate_one(robot, q, "planar", method="kernel")


_NO_NUMBA = textwrap.dedent(
    """
    import json, sys
    sys.modules["numba"] = None  # as on a machine without Numba: "import numba" fails
    import numpy as np
    import mobmanip
    from mobmanip.batch import analyze_batch, evaluate_one, kernel_available
    robot = mobmanip.load_robot("tiago_dual")
    qs = np.load(sys.argv[1])
    batch = analyze_batch(robot, qs, "spatial")
    single = [mobmanip.analyze(robot, q, "spatial") for q in qs]
    print(json.dumps({
        "kernel_available": kernel_available(),
        "numba_loaded": any(name.startswith("numba.") for name in sys.modules),
        "one_row_method": evaluate_one(robot, qs[0], "spatial").method,
        "svd_path": batch.svd_path.tolist(),
        "batch_kinematic": batch.kinematic.semi_axes.tolist(),
        "batch_dynamic": batch.dynamic.semi_axes.tolist(),
        "batch_dynamic_center": batch.dynamic.center.tolist(),
        "single_kinematic": [a.kinematic.semi_axes.tolist() for a in single],
        "single_dynamic": [a.dynamic.semi_axes.tolist() for a in single],
    }))
    """
)


def test_without_numba_the_numpy_fast_path_runs(tmp_path, rng):
    """In a process where Numba cannot be imported, mobmanip still imports, analyze_batch takes
    the stacked NumPy fast path (most rows certified, not the SVD path) and analyze the
    reference path; both equal analyze(method="exact") here to 1e-10 of each ellipsoid's size."""
    robot = mobmanip.load_robot("tiago_dual")
    qs = np.array(random_configurations(robot, rng, 40))
    np.save(tmp_path / "qs.npy", qs)
    script = tmp_path / "no_numba.py"
    script.write_text(_NO_NUMBA)
    done = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "qs.npy")],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
    )
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["kernel_available"] is False and out["numba_loaded"] is False
    assert out["one_row_method"] == "numpy"
    assert np.mean(out["svd_path"]) < 0.1  # the NumPy fast path certified nearly every row
    for i, q in enumerate(qs):
        exact = analyze(robot, q, "spatial", method="exact")
        k_scale = exact.kinematic.semi_axes[0]
        d_scale = max(exact.dynamic.semi_axes[0], np.linalg.norm(exact.dynamic.center))
        np.testing.assert_allclose(out["batch_kinematic"][i], exact.kinematic.semi_axes, rtol=0, atol=1e-10 * k_scale)
        np.testing.assert_allclose(out["batch_dynamic"][i], exact.dynamic.semi_axes, rtol=0, atol=1e-10 * d_scale)
        np.testing.assert_allclose(out["batch_dynamic_center"][i], exact.dynamic.center, rtol=0, atol=1e-10 * d_scale)
        np.testing.assert_allclose(out["single_kinematic"][i], exact.kinematic.semi_axes, rtol=0, atol=1e-12 * k_scale)
        np.testing.assert_allclose(out["single_dynamic"][i], exact.dynamic.semi_axes, rtol=0, atol=1e-12 * d_scale)
