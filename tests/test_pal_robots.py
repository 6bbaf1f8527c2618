"""Built-in TIAGo (one arm) and TIAGo Pro (four-wheeled, skid steer) from example-robot-data:
their geometry and limits against the URDF read independently, J_u against central differences
through ``pin.integrate``, and the kinetic energy of the reduced inertia."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.descriptions.urdf import read_urdf


@pytest.fixture(scope="module", params=["tiago", "tiago_pro"])
def pal(request):
    return mobmanip.load_robot(request.param)


def _random_q(robot, rng):
    lower, upper = robot.model.lowerPositionLimit.copy(), robot.model.upperPositionLimit.copy()
    lower[~np.isfinite(lower)], upper[~np.isfinite(upper)] = -1.0, 1.0
    q = pin.randomConfiguration(robot.model, lower, upper)
    yaw = rng.uniform(-math.pi, math.pi)
    q[:4] = (*rng.uniform(-1, 1, size=2), math.cos(yaw), math.sin(yaw))
    return q


def test_tiago_pro_sides_follow_the_urdf_wheels():
    robot = mobmanip.load_robot("tiago_pro")
    urdf = read_urdf(robot.spec.urdf)
    platform = robot.platform
    assert platform.kind == "skid_steer"
    wheels = ["wheel_front_right_joint", "wheel_rear_right_joint", "wheel_front_left_joint", "wheel_rear_left_joint"]
    limits = [(urdf.joints[w].limits.velocity, urdf.joints[w].limits.effort) for w in wheels]
    np.testing.assert_allclose(
        robot.velocity_limits[:2], [min(v for v, _ in limits[:2]), min(v for v, _ in limits[2:])]
    )
    np.testing.assert_allclose(robot.effort_limits[:2], [sum(e for _, e in limits[:2]), sum(e for _, e in limits[2:])])
    assert platform.radius == pytest.approx(0.0762, abs=1e-9)
    # Wheel centres at home, from Pinocchio's placements: the half-track is half the side distance.
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.neutral())
    y = {w: data.oMi[robot.model.getJointId(w)].translation[1] for w in wheels}
    expected = (y["wheel_front_left_joint"] + y["wheel_rear_left_joint"] - y["wheel_front_right_joint"]
                - y["wheel_rear_right_joint"]) / 4  # fmt: skip
    assert platform.half_track == pytest.approx(expected, abs=1e-12)
    # A side's wheels turn together: S's wheel rows of a side are equal up to each axis sign.
    S = robot.S
    v = [robot.model.joints[robot.model.getJointId(w)].idx_v for w in wheels]
    np.testing.assert_allclose(np.abs(S[v[0]]), np.abs(S[v[1]]))
    np.testing.assert_allclose(np.abs(S[v[2]]), np.abs(S[v[3]]))


def test_jacobian_and_kinetic_energy(pal, rng):
    frames = [arm.end_effector for arm in pal.arms]
    for _ in range(2):
        q, x = _random_q(pal, rng), rng.normal(size=pal.nx)
        J_u = mobmanip.unified_jacobian(pal, q, "translational")
        v, h = pal.S @ x, 1e-6

        def tips(qq):
            pin.framesForwardKinematics(pal.model, pal.data, qq)
            return np.concatenate([pal.data.oMf[pal.frame_id(f)].translation for f in frames])

        numeric = (tips(pin.integrate(pal.model, q, v * h)) - tips(pin.integrate(pal.model, q, -v * h))) / (2 * h)
        np.testing.assert_allclose(J_u @ x, numeric, atol=1e-7)
        P = mobmanip.reduced_dynamics(pal, q).P
        energy = pin.computeKineticEnergy(pal.model, pal.data, q, v)
        assert 0.5 * x @ P @ x == pytest.approx(energy, rel=1e-10)


def _unit_jacobian_ratio(robot, q) -> float:
    """Smallest over largest singular value of the hands' stacked world-aligned Jacobians (the
    arms' columns) scaled by the velocity limits: a singular posture gives about zero."""
    pin.computeJointJacobians(robot.model, robot.data, q)
    pin.updateFramePlacements(robot.model, robot.data)
    columns = [robot.model.joints[robot.model.getJointId(j)].idx_v for arm in robot.arms for j in arm.joint_names]
    J = np.vstack([pin.getFrameJacobian(robot.model, robot.data, robot.model.getFrameId(arm.end_effector),
                                        pin.LOCAL_WORLD_ALIGNED)[:, columns] for arm in robot.arms])  # fmt: skip
    sigma = np.linalg.svd(J * np.asarray(robot.velocity_limits)[robot.platform.n_reduced :], compute_uv=False)
    return float(sigma[-1] / sigma[0])


def test_tiago_pro_holds_its_object_in_front_with_the_arms_off_the_singularity():
    """TIAGo Pro's [hold]: tool frames 0.55 m ahead, 0.85 m high, 0.30 m apart (to the spec's
    4 decimals of a radian, 1e-4 m), each tool's z axis pointing at the other hand, every joint
    inside its range. By Pinocchio alone: home is singular (the hands' Jacobian loses rank), the
    hold is not."""
    robot = mobmanip.load_robot("tiago_pro")
    q = robot.hold_configuration()
    pin.framesForwardKinematics(robot.model, robot.data, q)
    hands = [robot.data.oMf[robot.model.getFrameId(arm.end_effector)] for arm in robot.arms]  # right, left
    for hand, side in zip(hands, (-1.0, 1.0)):
        np.testing.assert_allclose(hand.translation, [0.55, 0.15 * side, 0.85], atol=1e-4)
        np.testing.assert_allclose(hand.rotation[:, 2], [0.0, -side, 0.0], atol=1e-3)
    low, high = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    arms = [robot.model.joints[robot.model.getJointId(j)].idx_q for arm in robot.arms for j in arm.joint_names]
    assert np.all(q[arms] > low[arms] + 0.05) and np.all(q[arms] < high[arms] - 0.05)
    assert _unit_jacobian_ratio(robot, robot.neutral()) < 1e-3 < 0.05 < _unit_jacobian_ratio(robot, q)
