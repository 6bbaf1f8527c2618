"""The zero-moment point along a motion (mobmanip.motion.ground) against an independent reference:
the base wrench that Pinocchio's RNEA of the robot rebuilt with a free-flyer root needs for the
same motion is the floor's resultant; its zero-moment point must be the one mobmanip finds from
the centroidal momentum of its own planar-root model, to 1e-9 m."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from floor_reference import free_flyer_configuration, free_flyer_model, free_flyer_null_space
from mobmanip.motion.ground import ground_along
from mobmanip.motion.trajectory import Trajectory
from mobmanip.postures.named import named_configuration


def _random_motion(robot, q0, rng, n=6):
    qs = []
    for _ in range(n):
        q = q0.copy()
        yaw = rng.uniform(-math.pi, math.pi)
        q[:4] = (rng.uniform(-1, 1), rng.uniform(-1, 1), math.cos(yaw), math.sin(yaw))
        for arm in robot.arms:
            for name in arm.joint_names:
                joint = robot.model.joints[robot.model.getJointId(name)]
                q[joint.idx_q] += rng.uniform(-0.2, 0.2)
        qs.append(q)
    x = rng.normal(scale=0.5, size=(n, robot.nx))
    xdot = rng.normal(scale=2.0, size=(n, robot.nx))
    return Trajectory(np.arange(n, dtype=float), np.array(qs), x, xdot, np.zeros(n))


def _reference_zmp(robot, q, x, xdot, floor_z):
    model = free_flyer_model(robot)
    data = model.createData()
    q_f = free_flyer_configuration(robot, model, q)
    S_f = free_flyer_null_space(robot, model, q)
    assert np.allclose(robot.null_space_rate(q, x), 0.0)  # a differential drive: S is constant in its frame
    wrench = pin.rnea(model, data, q_f, S_f @ x, S_f @ xdot)[:6]  # at the base, in its frame
    pin.forwardKinematics(model, data, q_f)
    base = data.oMi[1]
    force = base.rotation @ wrench[:3]
    moment = base.rotation @ wrench[3:] + np.cross(base.translation, force)
    zmp = ((floor_z * force[0] - moment[1]) / force[2], (moment[0] + floor_z * force[1]) / force[2])
    return np.array(zmp), force[2]


@pytest.mark.parametrize("name", ["tiago_dual", "planar_dual_arm"])
def test_zmp_along_a_motion_equals_the_floating_base_rnea(name):
    robot = mobmanip.load_robot(name)
    q0 = named_configuration(robot, "hold") if name == "tiago_dual" else robot.neutral()
    motion = _random_motion(robot, q0, np.random.default_rng(7))
    task = robot.spec.default_task
    m = mobmanip.analyze(robot, q0, task).grasp_matrix.shape[0]
    ground = ground_along(robot, motion, np.zeros((len(motion), m)), task, object_mass=0.0)
    for i in range(len(motion)):
        zmp, normal = _reference_zmp(robot, motion.q[i], motion.x[i], motion.xdot[i], ground.support.floor_z)
        np.testing.assert_allclose(ground.zmp[i], zmp, atol=1e-9)
        assert ground.normal[i] == pytest.approx(normal, rel=1e-9)


def test_at_rest_the_zmp_is_below_the_centre_of_mass_with_the_object():
    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    still = Trajectory(
        np.array([0.0, 1.0]), np.array([q, q]), np.zeros((2, robot.nx)), np.zeros((2, robot.nx)), np.zeros(2)
    )
    ground = ground_along(robot, still, np.zeros((2, 6)), "spatial", object_mass=2.0)
    data = robot.model.createData()
    com = pin.centerOfMass(robot.model, data, q)
    analysis = mobmanip.analyze(robot, q, "spatial", object_mass=2.0)
    mass = pin.computeTotalMass(robot.model)
    both = (mass * com + 2.0 * analysis.held_object.center) / (mass + 2.0)
    np.testing.assert_allclose(ground.zmp[0], both[:2], atol=1e-12)
    assert ground.normal[0] == pytest.approx((mass + 2.0) * 9.81, rel=1e-12)
    assert ground.margin[0] > 0.0


def _reference_wrench(robot, q, x, xdot):
    """The floor's resultant on the robot (force, moment about the world origin; world axes) from
    the free-flyer RNEA."""
    model = free_flyer_model(robot)
    data = model.createData()
    q_f = free_flyer_configuration(robot, model, q)
    wrench = pin.rnea(model, data, q_f, free_flyer_null_space(robot, model, q) @ x,
                      free_flyer_null_space(robot, model, q) @ xdot)[:6]  # fmt: skip
    pin.forwardKinematics(model, data, q_f)
    base = data.oMi[1]
    force = base.rotation @ wrench[:3]
    return force, base.rotation @ wrench[3:] + np.cross(base.translation, force)


def _reference_contact_forces(support, q, force, moment, mu):
    """The contacts' forces, independently: the compliant normals as a + b x + c y with (a, b, c)
    from the floor's vertical force and horizontal moments (contacts on the floor plane); the
    wheels' longitudinal forces from the platform's longitudinal balance and its moment about the
    vertical; the lateral force (left open between the two wheels by the balance: they are
    collinear) half on each, as two equal tyres under a rigid platform share it."""
    yaw = math.atan2(q[3], q[2])
    e, u = np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)])
    points = support.world_points((q[0], q[1], yaw))
    z = support.floor_z
    xy = points[:, :2]
    # sum fn = Fz; sum fn y = M_x + z F_y; sum fn x = -M_y + z F_x (tangential forces act at height z)
    rhs = np.array([force[2], -moment[1] + z * force[0], moment[0] + z * force[1]])
    basis = np.column_stack([np.ones(len(xy)), xy])  # fn = basis @ (a, b, c)
    coef = np.linalg.solve(np.vstack([np.ones(len(xy)), xy.T]) @ basis, rhs)
    normal = basis @ coef
    driven = [k for k, c in enumerate(support.contacts) if c.driven]
    assert len(driven) == 2
    root = support.root_points()[driven]
    assert abs(root[0, 0] - root[1, 0]) < 1e-12  # the wheels on one axle, across the heading
    middle = points[driven, :2].mean(axis=0)
    side = (points[driven, :2] - middle) @ u  # the wheels' lateral offsets from the axle's middle
    cross = lambda a, b: a[0] * b[1] - a[1] * b[0]  # noqa: E731
    # sum l = F.e; sum l * side = moment of the longitudinal forces about the middle's vertical
    about_middle = moment[2] - cross(middle, force[:2])
    longitudinal = np.linalg.solve(np.array([[1.0, 1.0], side]), [force[:2] @ e, -about_middle])
    lateral = force[:2] @ u
    weight = mu * normal[driven]
    return normal, np.hypot(longitudinal, [lateral / 2.0, lateral / 2.0]) / weight


@pytest.mark.parametrize("name", ["tiago_dual", "planar_dual_arm"])
def test_contact_forces_along_a_motion_equal_an_independent_distribution(name):
    from mobmanip.motion.traction import traction_along

    robot = mobmanip.load_robot(name)
    q0 = named_configuration(robot, "hold") if name == "tiago_dual" else robot.neutral()
    motion = _random_motion(robot, q0, np.random.default_rng(11), n=12)
    m = mobmanip.analyze(robot, q0, robot.spec.default_task).grasp_matrix.shape[0]
    ground = ground_along(robot, motion, np.zeros((len(motion), m)), robot.spec.default_task, object_mass=0.0)
    traction = traction_along(ground, motion, 0.7)
    weight = pin.computeTotalMass(robot.model) * 9.81
    for i in range(len(motion)):
        force, moment = _reference_wrench(robot, motion.q[i], motion.x[i], motion.xdot[i])
        normal, use = _reference_contact_forces(ground.support, motion.q[i], force, moment, 0.7)
        np.testing.assert_allclose(traction.normal[i], normal, atol=1e-9 * weight)
        if np.all(normal[[c.driven for c in ground.support.contacts]] > 0):
            np.testing.assert_allclose(traction.use[i], use, rtol=1e-7)
    # the wheels carry the lateral force half each (the split the program once chose freely made
    # the two uses equal at some samples and not at others)
    yaw = np.arctan2(motion.q[:, 3], motion.q[:, 2])
    lateral = np.einsum("ikj,ij->ik", traction.tangential, np.column_stack([-np.sin(yaw), np.cos(yaw)]))
    np.testing.assert_allclose(lateral[:, 0], lateral[:, 1], rtol=1e-9, atol=1e-9 * weight)
