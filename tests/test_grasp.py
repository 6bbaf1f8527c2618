"""Grasp matrix W and object dynamics M_o, g_o (paper Eq. 17-22), checked against rigid-body mechanics.

Every expected value is computed here from first principles: the velocity of a point of a rigid
body (v + w x r), the net wrench of forces applied at points (sum f, sum r x f + n), and the
weight of a mass under Pinocchio's gravity. Each identity is then compared with what
``mobmanip.terms.grasp`` builds from the grasp offsets alone.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import scipy.linalg

import mobmanip
from mobmanip.analysis import analyze
from mobmanip.errors import TaskError
from mobmanip.robot.tasks import TASKS
from mobmanip.terms.grasp import HeldObject, grasp_block, grasp_matrix

# Rows of a 6-D twist/wrench [linear x, y, z, angular x, y, z] each task keeps, written out here
# from the task definitions in DESIGN.md (not read from the code under test).
TASK_ROWS = {
    "planar": (0, 1),
    "planar_rigid": (0, 1, 5),
    "translational": (0, 1, 2),
    "spatial": (0, 1, 2, 3, 4, 5),
}

# Entries of W are offsets (<= 1 m) and ones; products of a few such numbers: round-off ~1e-15.
# 1e-12 absolute is a safe bound for every identity below.
TOL = 1e-12


@pytest.fixture
def rng():
    return np.random.default_rng(7)


def _random_offsets(rng, k):
    return rng.uniform(-1.0, 1.0, size=(k, 3))


def _random_grasps(rng, count=20):
    """The offsets of ``count`` random grasps of one to three points each."""
    for _ in range(count):
        yield _random_offsets(rng, int(rng.integers(1, 4)))


def _twist_with_task_components(rng, rows):
    """A 6-D twist whose non-task components are zero (the object only moves in the task)."""
    twist = np.zeros(6)
    twist[list(rows)] = rng.normal(size=len(rows))
    return twist


def test_task_rows_match_the_design():
    assert {name: task.rows for name, task in TASKS.items()} == TASK_ROWS


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
@pytest.mark.parametrize("k", [1, 2, 3])
def test_grasp_matrix_is_the_row_of_blocks(task, k, rng):
    rows = TASK_ROWS[task]
    m = len(rows)
    offsets = _random_offsets(rng, k)
    W = grasp_matrix(task, offsets)
    assert W.shape == (m, m * k)
    for i, r in enumerate(offsets):
        np.testing.assert_array_equal(W[:, m * i : m * (i + 1)], grasp_block(task, r))


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_grasp_velocity_is_the_rigid_body_velocity_of_each_grasp_point(task, rng):
    """v_i = W_i^T v_o equals [v + w x r_i; w] of the grasp point, restricted to the task."""
    rows = list(TASK_ROWS[task])
    m = len(rows)
    for offsets in _random_grasps(rng):
        twist = _twist_with_task_components(rng, rows)
        v, w = twist[:3], twist[3:]
        W = grasp_matrix(task, offsets)
        v_o = twist[rows]
        stacked = W.T @ v_o
        for i, r in enumerate(offsets):
            point_twist = np.concatenate([v + np.cross(w, r), w])
            np.testing.assert_allclose(stacked[m * i : m * (i + 1)], point_twist[rows], rtol=0, atol=TOL)


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_W_maps_grasp_wrenches_to_the_net_wrench(task, rng):
    """W h = (sum f_i, sum r_i x f_i + n_i) restricted to the task."""
    rows = list(TASK_ROWS[task])
    m = len(rows)
    for offsets in _random_grasps(rng):
        k = len(offsets)
        wrenches = [_twist_with_task_components(rng, rows) for _ in range(k)]  # f, then n
        net = np.zeros(6)
        for r, h in zip(offsets, wrenches):
            f, n = h[:3], h[3:]
            net[:3] += f
            net[3:] += np.cross(r, f) + n
        h = np.concatenate([h[rows] for h in wrenches])
        W = grasp_matrix(task, offsets)
        assert h.shape == (m * k,)
        np.testing.assert_allclose(W @ h, net[rows], rtol=0, atol=TOL)


def _net_wrench(rows, offsets, h):
    """Net wrench of task-space grasp wrenches h (stacked), computed from the mechanics."""
    m = len(rows)
    net = np.zeros(6)
    for i, r in enumerate(offsets):
        full = np.zeros(6)
        full[rows] = h[m * i : m * (i + 1)]
        net[:3] += full[:3]
        net[3:] += np.cross(r, full[:3]) + full[3:]
    return net[rows]


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_pseudo_inverse_splits_a_wrench_without_internal_load(task, rng):
    """W W^+ = I; internal forces (I - W^+ W) y produce no net wrench; W^+ h_o has no internal part."""
    rows = list(TASK_ROWS[task])
    m = len(rows)
    for k in (1, 2, 3):
        offsets = _random_offsets(rng, k)
        W = grasp_matrix(task, offsets)
        W_pinv = np.linalg.pinv(W)
        np.testing.assert_allclose(W @ W_pinv, np.eye(m), rtol=0, atol=1e-10)
        np.testing.assert_allclose(W @ (np.eye(m * k) - W_pinv @ W), 0.0, rtol=0, atol=1e-10)
        # Internal forces: the null space of W, computed independently, gives zero net wrench
        # through the mechanics (not through W).
        internal = scipy.linalg.null_space(W)
        assert internal.shape[1] == m * (k - 1)
        for y in internal.T:
            np.testing.assert_allclose(_net_wrench(rows, offsets, y), 0.0, rtol=0, atol=1e-10)
        # W^+ h_o realises h_o and is orthogonal to every internal force.
        h_o = rng.normal(size=m)
        h = W_pinv @ h_o
        np.testing.assert_allclose(_net_wrench(rows, offsets, h), h_o, rtol=0, atol=1e-10)
        np.testing.assert_allclose(internal.T @ h, 0.0, rtol=0, atol=1e-10)


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_coincident_grasps_give_W_of_identities(task, rng):
    m = len(TASK_ROWS[task])
    point = rng.normal(size=3)
    obj = HeldObject.between(np.vstack([point, point]), mass=2.0)
    np.testing.assert_array_equal(obj.center, point)
    np.testing.assert_array_equal(obj.offsets, 0.0)
    np.testing.assert_array_equal(obj.grasp_matrix(task), np.hstack([np.eye(m), np.eye(m)]))
    # A point mass: no rotational inertia.
    np.testing.assert_array_equal(obj.inertia, 0.0)


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_one_grasp_gives_W_identity(task, rng):
    m = len(TASK_ROWS[task])
    obj = HeldObject.between(rng.normal(size=(1, 3)), mass=1.0)
    np.testing.assert_array_equal(obj.offsets, 0.0)
    np.testing.assert_array_equal(obj.grasp_matrix(task), np.eye(m))


def test_default_object_is_centred_at_the_centroid(rng):
    points = rng.normal(size=(3, 3))
    mass = 3.5
    obj = HeldObject.between(points, mass)
    np.testing.assert_allclose(obj.center, points.sum(axis=0) / 3, rtol=0, atol=TOL)
    np.testing.assert_allclose(obj.offsets, points - points.sum(axis=0) / 3, rtol=0, atol=TOL)
    np.testing.assert_allclose(obj.offsets.sum(axis=0), 0.0, rtol=0, atol=TOL)
    # Default inertia: solid sphere reaching the farthest grasp point, 2/5 m R^2.
    radius = max(np.sqrt(np.sum((p - points.mean(axis=0)) ** 2)) for p in points)
    np.testing.assert_allclose(obj.inertia, 0.4 * mass * radius**2 * np.eye(3), rtol=1e-14, atol=0)


@pytest.mark.parametrize("task", sorted(TASK_ROWS))
def test_object_inertia_and_gravity_in_every_task(task, rng):
    rows = list(TASK_ROWS[task])
    mass = 2.7
    A = rng.normal(size=(3, 3))
    inertia = A @ A.T + np.eye(3)
    obj = HeldObject(mass, inertia, np.zeros(3), np.zeros((1, 3)))
    full_inertia = np.zeros((6, 6))
    full_inertia[:3, :3] = mass * np.eye(3)
    full_inertia[3:, 3:] = inertia
    np.testing.assert_array_equal(obj.inertia_matrix(task), full_inertia[np.ix_(rows, rows)])
    # g_o: at rest M_o a_o + g_o = h_o, so the grasps push with -m g (Pinocchio's gravity, z up),
    # and a centred weight has no moment about the centre.
    gravity = pin.Model().gravity.linear
    weight = mass * gravity
    full_g = np.concatenate([-weight, np.zeros(3)])
    np.testing.assert_allclose(obj.gravity_vector(task), full_g[rows], rtol=1e-15, atol=0)
    if 2 in rows:
        assert obj.gravity_vector(task)[rows.index(2)] == pytest.approx(mass * 9.81, rel=1e-15)


def test_static_hold_balances_the_weight(rng):
    """Holding the object still: the grasp wrenches W^+ g_o and the weight sum to zero force and moment."""
    offsets = _random_offsets(rng, 2)
    offsets -= offsets.mean(axis=0)
    obj = HeldObject(1.8, np.eye(3) * 0.01, np.zeros(3), offsets)
    rows = list(TASK_ROWS["spatial"])
    W = obj.grasp_matrix("spatial")
    h = np.linalg.pinv(W) @ obj.gravity_vector("spatial")
    net = _net_wrench(rows, offsets, h)
    weight = obj.mass * pin.Model().gravity.linear
    np.testing.assert_allclose(net[:3] + weight, 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(net[3:], 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("mass", [-1.0, float("nan"), float("inf")])
def test_bad_object_mass_is_rejected(mass):
    with pytest.raises(TaskError):
        HeldObject.between(np.zeros((1, 3)), mass)


def test_analysis_uses_the_end_effector_centroid_and_its_offsets(rng):
    """analyze(): the default object sits between the end effectors (FK computed here)."""
    robot = mobmanip.load_robot("planar_dual_arm")
    joints = {name: float(rng.uniform(-np.pi, np.pi)) for arm in robot.arms for name in arm.joint_names}
    q = robot.configuration((0.4, -0.2, 0.9), joints)
    model = pin.buildModelFromUrdf(str(robot.spec.urdf), pin.JointModelPlanar())
    data = model.createData()
    q_own = pin.neutral(model)
    q_own[:4] = (0.4, -0.2, np.cos(0.9), np.sin(0.9))
    for name, value in joints.items():
        q_own[model.joints[model.getJointId(name)].idx_q] = value
    pin.framesForwardKinematics(model, data, q_own)
    tips = np.array([data.oMf[model.getFrameId(f"arm_{s}_tool_link")].translation for s in ("right", "left")])
    centre = tips.mean(axis=0)
    for task in ("planar", "planar_rigid", "spatial"):
        a = analyze(robot, q, task)
        np.testing.assert_allclose(a.held_object.center, centre, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.held_object.offsets, tips - centre, rtol=0, atol=1e-12)
        # W is the one of the object's offsets, which are the FK tips' up to rounding
        np.testing.assert_allclose(a.grasp_matrix, grasp_matrix(task, a.held_object.offsets), rtol=0, atol=0)
        np.testing.assert_allclose(a.grasp_matrix, grasp_matrix(task, tips - centre), rtol=0, atol=1e-12)
        assert a.held_object.mass == 2.0  # the spec's object mass (Table 2)
        np.testing.assert_array_equal(a.held_object.inertia_matrix(task)[:2, :2], 2.0 * np.eye(2))
    # planar: W = [I I] whatever the offsets (rotation is not in the task).
    np.testing.assert_array_equal(analyze(robot, q, "planar").grasp_matrix, np.hstack([np.eye(2), np.eye(2)]))
