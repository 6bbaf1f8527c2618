"""analyze_batch: the stacked analysis equals the single-configuration analyze, row by row."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mobmanip
from conftest import random_configurations
from mobmanip.analysis import analyze
from mobmanip.batch import EllipsoidBatch, analyze_batch
from mobmanip.errors import ConfigurationError, TaskError
from mobmanip.robot.tasks import get_task
from mobmanip.sets.ellipsoid import dynamic_ellipsoid

TOL = 1e-10  # relative to the ellipsoid's size: max(largest semi-axis, |centre|)
_EPS = np.finfo(float).eps


def assert_same_ellipsoid(batch_e, single_e, label="", tol=TOL):
    """Equal to tol of the ellipsoid's size: semi-axes, centre, G G^T, axes up to sign, flags."""
    assert batch_e.degenerate == single_e.degenerate, label
    assert batch_e.empty == single_e.empty, label
    scale = max(float(single_e.semi_axes[0]), float(np.linalg.norm(single_e.center)), 1e-300)
    np.testing.assert_allclose(batch_e.semi_axes, single_e.semi_axes, rtol=0, atol=tol * scale, err_msg=label)
    np.testing.assert_allclose(batch_e.center, single_e.center, rtol=0, atol=tol * scale, err_msg=label)
    Gb, Gs = batch_e.generator, single_e.generator
    np.testing.assert_allclose(Gb @ Gb.T, Gs @ Gs.T, rtol=0, atol=tol * scale**2, err_msg=label)
    # axes up to sign, where the semi-axis is positive and clearly apart from its neighbours
    s = single_e.semi_axes
    for k in range(len(s)):
        gaps = [abs(s[k] - s[j]) for j in range(len(s)) if j != k]
        if s[k] > 1e-6 * scale and min(gaps, default=np.inf) > 1e-3 * scale:
            dot = abs(float(batch_e.axes[k] @ single_e.axes[k]))
            assert dot == pytest.approx(1.0, abs=1e-8), (label, k)
    assert batch_e.volume == pytest.approx(single_e.volume, rel=0, abs=tol * max(single_e.volume, scale**batch_e.dim))
    assert batch_e.isotropy == pytest.approx(single_e.isotropy, abs=1e-8)


def assert_batch_equals_single(robot, qs, task, decoupled=False, object_mass=None, method="auto", tol=TOL):
    batch = analyze_batch(robot, qs, task, decoupled=decoupled, object_mass=object_mass, method=method)
    assert len(batch) == len(qs)
    for i, q in enumerate(qs):
        single = analyze(robot, q, task, decoupled=decoupled, object_mass=object_mass, method="exact")
        assert_same_ellipsoid(batch.kinematic[i], single.kinematic, f"kinematic row {i}", tol)
        assert_same_ellipsoid(batch.dynamic[i], single.dynamic, f"dynamic row {i}", tol)
    return batch


@pytest.mark.parametrize("task", ["planar", "planar_rigid", "translational", "spatial"])
@pytest.mark.parametrize("platform", ["own", "fixed"])
def test_paper_robot_random_configurations(robot, rng, task, platform):
    r = robot if platform == "own" else robot.with_platform("fixed")
    qs = np.array(random_configurations(r, rng, 40))
    for decoupled in (False, True):
        batch = assert_batch_equals_single(r, qs, task, decoupled=decoupled)
    if task in ("translational", "spatial"):
        # the planar robot cannot move its object out of the plane: degenerate everywhere
        assert batch.kinematic.degenerate.all() and batch.dynamic.degenerate.all()
        assert batch.svd_path.all()


@pytest.mark.parametrize("task", ["spatial", "translational", "planar_rigid"])
@pytest.mark.parametrize("platform", ["own", "fixed"])
def test_tiago_random_configurations(tiago, rng, task, platform):
    r = tiago if platform == "own" else tiago.with_platform("fixed")
    qs = np.array(random_configurations(r, rng, 30))
    assert_batch_equals_single(r, qs, task, decoupled=False)
    assert_batch_equals_single(r, qs, task, decoupled=True)
    # the same fast path stacked in NumPy, independent of the compiled kernel
    assert_batch_equals_single(r, qs, task, decoupled=True, method="numpy")


def test_svd_path_equals_single(robot, tiago, rng):
    """The stacked mirror of mobmanip.sets.ellipsoid, forced on every row."""
    for r, task in (
        (robot, "planar"),
        (robot, "planar_rigid"),
        (tiago, "spatial"),
        (tiago.with_platform("fixed"), "spatial"),
    ):
        qs = np.array(random_configurations(r, rng, 15))
        batch = assert_batch_equals_single(r, qs, task, method="svd")
        assert batch.svd_path.all()


def stretched(robot, angle=0.3, heading=0.2):
    """Both arms of the paper's robot straight out towards the object (each arm singular)."""
    joints = {}
    for arm in robot.arms:
        joints.update(zip(arm.joint_names, (angle, 0.0, 0.0)))
    return robot.configuration((0.4, -0.1, heading), joints)


def test_stretched_arms_degenerate(robot):
    """Arms stretched: the fixed dual-arm system cannot move the object along the arms."""
    fixed = robot.with_platform("fixed")
    q = stretched(fixed)
    nearly = stretched(fixed)
    for arm, bend in zip(fixed.arms, (1e-5, -1e-5)):  # ill-conditioned, not singular
        nearly[fixed.model.joints[fixed.model.getJointId(arm.joint_names[1])].idx_q] = bend
    qs = np.array([q, nearly, q])
    batch = assert_batch_equals_single(fixed, qs, "planar")
    assert batch.kinematic.degenerate[0] and batch.kinematic.degenerate[2]
    assert batch.kinematic.semi_axes[0, -1] == 0.0
    assert not batch.kinematic.degenerate[1]
    assert 0.0 < batch.kinematic.semi_axes[1, -1] < 1e-3 * batch.kinematic.semi_axes[1, 0]
    assert batch.svd_path[0] and batch.svd_path[2]  # a singular row is never certified for the fast path
    # with the platform moving, the wheels restore the lost direction
    moving = assert_batch_equals_single(robot, qs[[0, 2]], "planar")
    assert not moving.kinematic.degenerate[0]
    # The nearly stretched row is ill-conditioned (kappa(J_u) ~ 6e5): no computation can promise
    # more than ~kappa eps there. A 1-ulp change of J_u's entries moves the exact path's own
    # dynamic ellipsoid (G G^T) by ~2e-10 of its size squared, and the batch takes its positions
    # and M from a different (equally exact) Pinocchio call than the single path.
    exact = analyze(robot, nearly, "planar", method="exact")
    J_u = exact.unified_jacobian
    kappa = np.linalg.cond(J_u)
    assert kappa > 1e5
    rng = np.random.default_rng(1)
    spread = 0.0
    for _ in range(5):
        bumped = J_u * (1.0 + _EPS * rng.choice([-1.0, 1.0], J_u.shape))
        d = dynamic_ellipsoid(
            bumped,
            exact.grasp_matrix,
            exact.reduced_inertia,
            robot.Q,
            exact.bias,
            exact.held_object.inertia_matrix(get_task("planar")),
            exact.held_object.gravity_vector(get_task("planar")),
            robot.effort_limits,
        )
        G, G0 = d.generator, exact.dynamic.generator
        spread = max(spread, np.abs(G @ G.T - G0 @ G0.T).max() / exact.dynamic.semi_axes[0] ** 2)
    assert spread > TOL  # the claim of TOL is beyond this row's conditioning ...
    assert_batch_equals_single(robot, qs[1:2], "planar", tol=10.0 * kappa * _EPS)  # ... kappa eps is not


def test_gravity_and_empty(tiago, rng):
    """TIAGo++ holding an object in the spatial task: gravity shifts the dynamic ellipsoid, and a
    heavy object makes it empty (the torques cannot hold it), as in the single path."""
    qs = np.array(random_configurations(tiago, rng, 25))
    light = assert_batch_equals_single(tiago, qs, "spatial", object_mass=1.0)
    assert_batch_equals_single(tiago, qs, "spatial", object_mass=60.0, method="numpy")
    assert np.all(np.linalg.norm(light.dynamic.center, axis=1) > 0.0)
    heavy = assert_batch_equals_single(tiago, qs, "spatial", object_mass=60.0)
    assert heavy.dynamic.empty.any()
    assert np.all(heavy.dynamic.semi_axes[heavy.dynamic.empty] == 0.0)
    assert not heavy.kinematic.empty.any()


def test_results_do_not_depend_on_chunking(tiago, rng):
    qs = np.array(random_configurations(tiago, rng, 23))
    a = analyze_batch(tiago, qs, chunk_size=2048)
    b = analyze_batch(tiago, qs, chunk_size=5)
    for name in ("semi_axes", "center", "matrix"):
        np.testing.assert_allclose(getattr(a.kinematic, name), getattr(b.kinematic, name), rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(getattr(a.dynamic, name), getattr(b.dynamic, name), rtol=1e-13, atol=1e-13)


def test_positions_and_object_centres(tiago, robot, rng):
    qs = np.array(random_configurations(tiago, rng, 4))
    batch = analyze_batch(tiago, qs)
    for i, q in enumerate(qs):
        single = analyze(tiago, q)
        np.testing.assert_allclose(batch.end_effector_positions[i], single.end_effector_positions, atol=1e-14)
        np.testing.assert_allclose(batch.object_centers[i], single.held_object.center, atol=1e-14)
    planar = analyze_batch(robot, np.array(random_configurations(robot, rng, 3)))
    assert planar.end_effector_positions is None  # not needed by the planar grasp
    assert analyze_batch(robot, planar.qs, positions=True).end_effector_positions.shape == (3, 2, 3)


def test_ellipsoid_batch_indices_match_single(tiago, rng):
    qs = np.array(random_configurations(tiago, rng, 6))
    batch = analyze_batch(tiago, qs)
    d = rng.normal(size=6)
    for i, q in enumerate(qs):
        single = analyze(tiago, q).dynamic
        row = batch.dynamic[i]
        scale = single.semi_axes[0]
        assert batch.dynamic.radius_along(d)[i] == pytest.approx(single.radius_along(d), abs=TOL * scale)
        assert batch.dynamic.support(d)[i] == pytest.approx(single.support(d), abs=TOL * scale * np.linalg.norm(d))
        assert batch.dynamic.volume[i] == pytest.approx(row.volume, rel=1e-14)
        assert batch.dynamic.isotropy[i] == pytest.approx(row.isotropy, rel=1e-14)
        assert batch.dynamic.manipulability[i] == pytest.approx(row.manipulability, rel=1e-14)
    # the matrix is the inverse of the generator Gram on the ellipsoid's span
    G = batch.kinematic.generator
    product = batch.kinematic.matrix @ G @ np.swapaxes(G, 1, 2)
    np.testing.assert_allclose(product, np.broadcast_to(np.eye(6), product.shape), atol=1e-8)


def test_empty_and_single_row_batches(robot):
    q = robot.neutral()
    one = analyze_batch(robot, q[None, :])
    assert len(one) == 1 and one.kinematic.semi_axes.shape == (1, 2)
    none = analyze_batch(robot, np.zeros((0, robot.model.nq)))
    assert len(none) == 0 and none.dynamic.semi_axes.shape == (0, 2)
    assert isinstance(none.kinematic, EllipsoidBatch)


def test_bad_configurations_name_row_and_joint(robot):
    qs = np.tile(robot.neutral(), (5, 1))
    name = robot.arms[1].joint_names[2]
    index = robot.model.joints[robot.model.getJointId(name)].idx_q
    qs[3, index] = math.nan
    with pytest.raises(ConfigurationError, match=rf"row 3, entry {index} \(joint '{name}'\) is nan"):
        analyze_batch(robot, qs)
    with pytest.raises(ConfigurationError, match=r"shape \(N, 14\)"):
        analyze_batch(robot, robot.neutral())
    with pytest.raises(ConfigurationError, match=r"shape \(N, 14\)"):
        analyze_batch(robot, np.zeros((3, 13)))
    with pytest.raises(TaskError, match="object mass"):
        analyze_batch(robot, qs[:1], object_mass=-1.0)
    with pytest.raises(TaskError, match="unknown task"):
        analyze_batch(robot, qs[:1], task="sideways")


def test_exported_from_package():
    assert mobmanip.analyze_batch is analyze_batch


def test_svd_rows_queued_over_chunks_equal_rows_computed_per_chunk(tiago, rng):
    """analyze_batch queues the SVD path's rows of all chunks and computes them at once: the
    same ellipsoids as computing them chunk by chunk, also where chunks use different limits
    (queued items are grouped by their limits)."""
    from mobmanip.batch import BatchSetup, SvdBacklog, ellipsoids_from_terms, iter_terms

    qs = np.array(random_configurations(tiago, rng, 12))
    setup = BatchSetup(tiago, "spatial")
    scales = (1.0, 1.0, 0.5)  # chunks of 4: the first two share their limits
    results = {}
    for queued in (False, True):
        kin, dyn = EllipsoidBatch.allocate(len(qs), setup.m), EllipsoidBatch.allocate(len(qs), setup.m)
        backlog = SvdBacklog(setup) if queued else None
        for (start, t), scale in zip(iter_terms(setup, qs, 4), scales):
            svd_rows = ellipsoids_from_terms(
                setup,
                t,
                velocity_limits=scale * tiago.velocity_limits,
                effort_limits=scale * tiago.effort_limits,
                kinematic=kin,
                dynamic=dyn,
                offset=start,
                method="svd",
                backlog=backlog,
            )
            assert svd_rows.all()
        if queued:
            assert len(backlog.dynamic) == 3 and not np.any(dyn.semi_axes)  # nothing computed yet
            backlog.flush(kin, dyn)
            assert not backlog.dynamic and not backlog.kinematic
        results[queued] = (kin, dyn)
    for per_chunk, queued in zip(results[False], results[True]):
        for name in ("center", "semi_axes", "axes", "matrix", "degenerate", "empty"):
            np.testing.assert_array_equal(getattr(queued, name), getattr(per_chunk, name))
