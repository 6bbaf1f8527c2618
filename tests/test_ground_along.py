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
