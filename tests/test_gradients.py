"""Analytic gradients of the ellipsoids' measures against central differences through pin.integrate.

The differences are taken of the reference implementation's values (``analyze_batch`` on its SVD
path, the stacked mirror of :mod:`mobmanip.sets.ellipsoid`), not of the gradient module's own values,
so a test also checks that both compute the same measure.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import random_configuration
from mobmanip.errors import ArgumentError, MeasureError, ModelError
from mobmanip.gradients import INDICES, GradientEvaluator, Objective, measure_gradient, platform_gradient
from mobmanip.gradients import derivatives as derivatives
from mobmanip.gradients.derivatives import DerivativeWorkspace, frame_jacobian_derivative, hessian_layout
from mobmanip.robot.tasks import get_task
from mobmanip.terms.dynamics import mass_matrix

ROBOTS = ("planar_dual_arm", "tiago_dual", "tiago_dual_torso", "planar_dual_arm_omni", "ur5")
STEP = 1e-4  # rad or m: fourth-order central differences, truncation ~ STEP^4 (scaled down near
# a singularity, where the measures' higher derivatives grow, see _steps)
RTOL = 1e-6  # the bound on ||gradient - differences|| / ||differences||


@pytest.fixture(scope="module")
def robots():
    return {name: mobmanip.load_robot(name) for name in ROBOTS}


def _steps(batch):
    """Difference steps per configuration: STEP, shrunk in proportion to the ellipsoids' isotropy
    below 0.05 (near a singular posture the measures curve sharply), never below 1e-6."""
    iso = np.minimum(batch.kinematic.semi_axes[:, -1] / batch.kinematic.semi_axes[:, 0],
                     batch.dynamic.semi_axes[:, -1] / np.maximum(batch.dynamic.semi_axes[:, 0], 1e-300))  # fmt: skip
    return STEP * np.clip(20.0 * iso, 1e-2, 1.0)


def _stencil(robot, qs, steps):
    """Configurations q (+/-) h e_k and (+/-) 2h e_k for every q and tangent direction k, (N, 4, nv, nq)."""
    model = robot.model
    nv = model.nv
    out = np.empty((len(qs), 4, nv, model.nq))
    for i, q in enumerate(qs):
        for k in range(nv):
            e = np.zeros(nv)
            e[k] = steps[i]
            for s, factor in enumerate((2.0, 1.0, -1.0, -2.0)):
                out[i, s, k] = pin.integrate(model, q, factor * e)
    return out


def _differences(values, steps):
    """Fourth-order central differences from values at (+2h, +h, -h, -2h), (N, 4, nv) -> (N, nv)."""
    return (-values[:, 0] + 8.0 * values[:, 1] - 8.0 * values[:, 2] + values[:, 3]) / (12.0 * steps[:, None])


def _reference_index(batch, index, direction):
    """An index of reference ellipsoids (EllipsoidBatch) by its definition, (N,)."""
    s = batch.semi_axes
    m = s.shape[1]
    if index == "log_volume":
        return 0.5 * m * math.log(math.pi) - math.lgamma(0.5 * m + 1.0) + np.sum(np.log(s), axis=1)
    if index == "log_isotropy":
        return np.mean(np.log(s**2), axis=1) - np.log(np.mean(s**2, axis=1))
    if index == "capacity":
        along = np.einsum("nkj,j->nk", batch.axes, direction)
        return batch.center @ direction + np.sqrt(np.sum((s * along) ** 2, axis=1))
    return s[:, -1]


def _usable(batch):
    """Neither degenerate nor empty, and not within isotropy 1e-3 of a singular posture (there the
    measures head for -inf and no difference step is both small enough and above round-off)."""
    iso = batch.semi_axes[:, -1] / np.maximum(batch.semi_axes[:, 0], 1e-300)
    return ~(batch.degenerate | batch.empty) & (iso >= 1e-3)


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("loaded", [False, True], ids=["no_load", "load"])
def test_gradients_equal_central_differences(robots, name, loaded):
    """On 100 random configurations, kinematic and dynamic, every index: relative error < 1e-6."""
    robot = robots[name]
    task = get_task(robot.spec.default_task)
    mass = 3.0 if loaded else 0.0
    rng = np.random.default_rng(13 + len(name) + int(loaded))
    qs = np.array([random_configuration(robot, rng) for _ in range(140)])
    nv = robot.model.nv
    at = mobmanip.analyze_batch(robot, qs, object_mass=mass, method="svd")
    steps = _steps(at)
    stencil = _stencil(robot, qs, steps)
    around = mobmanip.analyze_batch(robot, stencil.reshape(-1, robot.model.nq), object_mass=mass, method="svd")
    for ellipsoid in ("kinematic", "dynamic"):
        ref_at, ref_around = getattr(at, ellipsoid), getattr(around, ellipsoid)
        usable = _usable(ref_at) & _usable(ref_around).reshape(len(qs), -1).all(axis=1)
        rows = np.flatnonzero(usable)[:100]
        assert len(rows) == 100, f"{name} {ellipsoid}: only {len(rows)} usable configurations"
        s = ref_at.semi_axes[rows]
        simple = (s[:, -2] - s[:, -1]) > 1e-3 * s[:, 0]  # minor axis differentiable (simple eigenvalue)
        for index in INDICES:
            direction = None
            if index == "capacity":  # along the last task axis (z, or yaw): gravity shifts the centre there
                direction = tuple(np.eye(task.dim)[-1])
            objective = Objective(ellipsoid, index, direction)
            ev = GradientEvaluator(robot, objective, object_mass=mass)
            got = ev.batch(qs[rows])
            assert got.defined.all()
            d = None if direction is None else np.asarray(direction)
            want_value = _reference_index(ref_at, index, d)[rows]
            np.testing.assert_allclose(got.value, want_value, rtol=1e-9, atol=1e-12)
            values = _reference_index(ref_around, index, d).reshape(len(qs), 4, nv)[rows]
            fd = _differences(values, steps[rows])
            keep = simple if index == "minor_axis" else np.ones(len(rows), dtype=bool)
            assert keep.sum() >= 80
            error = np.linalg.norm(got.gradient - fd, axis=1) / np.linalg.norm(fd, axis=1)
            assert error[keep].max() < RTOL, (name, ellipsoid, index, error[keep].max())


def test_hessian_reading_matches_differences_on_tiago(robots):
    """The layout detected on Pinocchio's sample arm reads TIAGo++'s frame Hessians right."""
    robot = robots["tiago_dual"]
    model, data = robot.model, robot.data
    q = random_configuration(robot, np.random.default_rng(5))
    frame = robot.arms[1].frame_id

    def jacobian(qq):
        pin.computeJointJacobians(model, data, qq)
        pin.updateFramePlacements(model, data)
        return pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED).copy()

    fd = np.zeros((6, model.nv, model.nv))
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = STEP
        fd[:, :, k] = (
            -jacobian(pin.integrate(model, q, 2 * e))
            + 8 * jacobian(pin.integrate(model, q, e))
            - 8 * jacobian(pin.integrate(model, q, -e))
            + jacobian(pin.integrate(model, q, -2 * e))
        ) / (12 * STEP)
    jacobian(q)
    pin.computeJointKinematicHessians(model, data)
    H = frame_jacobian_derivative(model, data, frame)
    np.testing.assert_allclose(H, fd, atol=1e-9)
    assert hessian_layout() in ("c", "fortran")


def test_a_pinocchio_with_the_layout_fixed_is_read_right(robots, monkeypatch):
    """Simulate a Pinocchio whose getters return correctly laid-out arrays: the detection switches
    to ``"c"`` and the derivatives stay right."""
    robot = robots["planar_dual_arm"]
    original_frame, original_joint = pin.getFrameKinematicHessian, pin.getJointKinematicHessian
    was = hessian_layout()

    def fixed(getter):
        def call(*args):
            H = getter(*args)
            return np.ascontiguousarray(H.ravel("C").reshape(H.shape, order="F")) if was == "fortran" else H

        return call

    q = random_configuration(robot, np.random.default_rng(8))
    before = DerivativeWorkspace(robot, "planar").evaluate(q[None])
    monkeypatch.setattr(pin, "getFrameKinematicHessian", fixed(original_frame))
    monkeypatch.setattr(pin, "getJointKinematicHessian", fixed(original_joint))
    derivatives.hessian_layout.cache_clear()
    try:
        assert hessian_layout() == "c"
        after = DerivativeWorkspace(robot, "planar").evaluate(q[None])
    finally:
        derivatives.hessian_layout.cache_clear()
    np.testing.assert_allclose(after.dJ, before.dJ, atol=1e-14)
    np.testing.assert_allclose(after.dM, before.dM, atol=1e-12)


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual_torso"])
def test_mass_matrix_derivative_equals_rnea_derivatives(robots, name):
    """dM/dq from the bodies' local Hessians equals d(tau)/dq of RNEA at v = 0, a = e_i, minus
    dg/dq (an independent Pinocchio algorithm); M equals CRBA's."""
    robot = robots[name]
    model, data = robot.model, robot.data
    q = random_configuration(robot, np.random.default_rng(21))
    d = DerivativeWorkspace(robot, robot.spec.default_task).evaluate(q[None])
    np.testing.assert_allclose(d.M[0], mass_matrix(robot, q), atol=1e-12)
    zero = np.zeros(model.nv)
    dg = pin.computeGeneralizedGravityDerivatives(model, data, q).copy()
    np.testing.assert_allclose(d.dg[0], dg.T, atol=1e-12)
    for i in range(model.nv):
        a = np.zeros(model.nv)
        a[i] = 1.0
        dtau_dq, _, _ = pin.computeRNEADerivatives(model, data, q, zero, a)
        # column i of M, differentiated along every k: dM[k, :, i]
        np.testing.assert_allclose(d.dM[0][:, :, i].T, dtau_dq - dg, atol=1e-10)


def test_platform_gradient_is_the_world_derivative(robots):
    """The root joint's tangent entries turned into world x, y and heading equal differences
    of the measure when the platform pose (x, y, heading) is changed through Robot.configuration."""
    robot = robots["tiago_dual"]
    ev = GradientEvaluator(robot, "dynamic:capacity:+x", object_mass=1.0)
    joints = robot.configuration_dict(random_configuration(robot, np.random.default_rng(3)))["joints"]
    pose = np.array([0.4, -1.2, 2.1])
    q = robot.configuration(tuple(pose), joints)
    _, g, ok = ev(q)
    assert ok
    want = np.zeros(3)
    for k in range(3):
        e = np.zeros(3)
        e[k] = STEP
        vals = [ev(robot.configuration(tuple(pose + f * e), joints))[0] for f in (2, 1, -1, -2)]
        want[k] = (-vals[0] + 8 * vals[1] - 8 * vals[2] + vals[3]) / (12 * STEP)
    np.testing.assert_allclose(platform_gradient(q, g), want, rtol=1e-7, atol=1e-9)
    # a capacity measure does not change when the platform translates, so its x and y parts are
    # zero on both sides above; the map's translation part is checked on a function that does
    # depend on where the platform is: f = a . (a hand's world position)
    model, data = robot.model, robot.model.createData()
    frame = robot.arms[0].frame_id
    weights = np.array([1.0, 2.0, 0.0])

    def f(qq):
        pin.framesForwardKinematics(model, data, qq)
        return float(weights @ data.oMf[frame].translation)

    tangent = np.zeros(model.nv)
    for k in range(3):
        e = np.zeros(model.nv)
        e[k] = STEP
        tangent[k] = (f(pin.integrate(model, q, e)) - f(pin.integrate(model, q, -e))) / (2 * STEP)
    world = np.zeros(3)
    for k in range(3):
        e = np.zeros(3)
        e[k] = STEP
        world[k] = (
            f(robot.configuration(tuple(pose + e), joints)) - f(robot.configuration(tuple(pose - e), joints))
        ) / (2 * STEP)
    np.testing.assert_allclose(world[:2], weights[:2], atol=1e-6)  # translating the platform moves the hand
    np.testing.assert_allclose(platform_gradient(q, tangent), world, atol=1e-6)


def test_explicit_object_is_constant(robots):
    """With an explicit HeldObject (W, M_o, g_o fixed), the gradient equals differences of
    analyze(held_object=...) (the reference path)."""
    robot = robots["tiago_dual"]
    obj = mobmanip.terms.grasp.HeldObject(
        2.0, np.diag([0.02, 0.03, 0.04]), np.zeros(3), np.array([[0.0, -0.15, 0.0], [0.0, 0.15, 0.0]])
    )
    q = random_configuration(robot, np.random.default_rng(34))
    value, g = measure_gradient(robot, q, "dynamic:log_volume", held_object=obj)
    model = robot.model

    def reference(qq):
        return math.log(mobmanip.analyze(robot, qq, held_object=obj, method="exact").dynamic.volume)

    assert value == pytest.approx(reference(q), rel=1e-12)
    fd = np.zeros(model.nv)
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = STEP
        vals = [reference(pin.integrate(model, q, f * e)) for f in (2, 1, -1, -2)]
        fd[k] = (-vals[0] + 8 * vals[1] - 8 * vals[2] + vals[3]) / (12 * STEP)
    assert np.linalg.norm(g - fd) / np.linalg.norm(fd) < RTOL


def test_singular_posture_is_not_differentiable(robots):
    """Straight arms (a singular posture) give no gradient: flagged in a batch, an error alone."""
    robot = robots["planar_dual_arm"].with_platform("fixed")
    q = robot.neutral()  # every arm joint at zero: both arms stretched out
    ev = GradientEvaluator(robot, "kinematic:log_volume")
    batch = ev.batch(q[None])
    assert not batch.defined[0]
    assert batch.value[0] == 0.0 and not batch.gradient.any()
    with pytest.raises(MeasureError, match="not differentiable"):
        measure_gradient(robot, q, "kinematic:log_volume")


def test_objective_parsing_and_errors(robots):
    robot = robots["tiago_dual"]
    assert Objective.parse("kinematic:capacity:-z", "spatial").direction == (0, 0, -1.0, 0, 0, 0)
    assert Objective.parse("dynamic:capacity:1,1,0", "translational").direction == pytest.approx(
        (2**-0.5, 2**-0.5, 0.0)
    )
    with pytest.raises(MeasureError, match="'kinematic_polytope' has no gradient"):
        Objective.parse("kinematic_polytope:log_volume", "planar")
    with pytest.raises(MeasureError, match="'volume' is not known for the dynamic"):
        Objective.parse("dynamic:volume", "planar")
    with pytest.raises(ArgumentError, match="needs a direction"):
        Objective.parse("dynamic:capacity", "planar")
    with pytest.raises(ArgumentError, match="'north'"):
        Objective.parse("dynamic:capacity:north", "planar")
    with pytest.raises(ArgumentError, match="has 2 components"):
        GradientEvaluator(robot, Objective("kinematic", "capacity", (1.0, 0.0)))
    with pytest.raises(ArgumentError, match="finite and nonzero"):
        Objective("kinematic", "capacity", (0.0, 0.0))


def test_steered_platform_is_refused(tmp_path):
    """S(q) of a steered platform depends on q; its gradient is refused, naming the kind."""
    from test_steered import write_tricycle

    robot = mobmanip.load_robot(write_tricycle(tmp_path))
    with pytest.raises(ModelError, match="'steered'"):
        GradientEvaluator(robot, "kinematic:log_volume")
