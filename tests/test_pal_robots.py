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
