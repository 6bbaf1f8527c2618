"""Hostile and broken input (5): extreme but finite numbers. Results do not depend on where the
platform stands and turn with its heading; multiplying every limit of one kind by a factor from
1e-6 to 1e6 scales the ellipsoids as the mathematics says, or the input is refused with the
range; at the edge of the supported ratio of limits the ellipsoids match a 60-digit computation."""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.errors import ConfigurationError, RangeError
from mobmanip.support.ranges import LIMIT_RATIO, PLATFORM_POSITION

FACTORS = (1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6)
RTOL = 1e-9  # of each ellipsoid's size


@pytest.fixture(scope="module")
def q45(paper):
    return configuration_at(paper, optimal_posture(paper), angle_deg=45.0)


def _placed(robot, q, x, y, yaw):
    out = q.copy()
    out[:4] = (x, y, math.cos(yaw), math.sin(yaw))
    return out


def _close(a, b, scale, rtol):
    return np.abs(np.asarray(a) - np.asarray(b)).max() <= rtol * scale


@pytest.mark.parametrize("xy", [(1.0, -2.0), (1e3, 1e3), (-1e5, 3e4), (PLATFORM_POSITION, -PLATFORM_POSITION)])
def test_results_do_not_depend_on_where_the_platform_stands(paper, q45, xy):
    here = mobmanip.analyze(paper, _placed(paper, q45, 0.0, 0.0, 0.3))
    there = mobmanip.analyze(paper, _placed(paper, q45, *xy, 0.3))
    for name in ("kinematic", "dynamic"):
        a, b = here.measures[name], there.measures[name]
        assert _close(a.semi_axes, b.semi_axes, a.semi_axes[0], 1e-8)
        assert _close(a.generator @ a.generator.T, b.generator @ b.generator.T, a.semi_axes[0] ** 2, 1e-8)
    shift = np.array([*xy, 0.0])
    assert np.allclose(there.held_object.center - shift, here.held_object.center, atol=1e-9 * max(1.0, abs(xy[0])))


def test_a_platform_beyond_the_supported_range_is_refused(paper, q45):
    for x in (2 * PLATFORM_POSITION, 1e13, -1e300):
        with pytest.raises(ConfigurationError, match="outside the supported range"):
            mobmanip.analyze(paper, _placed(paper, q45, x, 0.0, 0.0))
        with pytest.raises(ConfigurationError, match="row 1"):
            mobmanip.analyze_batch(paper, np.array([q45, _placed(paper, q45, 0.0, x, 0.0)]))


@pytest.mark.parametrize("heading_deg", [30.0, 90.0, 200.0, -135.0])
def test_results_turn_with_the_platform_heading(paper, q45, heading_deg):
    base = mobmanip.analyze(paper, _placed(paper, q45, 0.5, 0.5, 0.0))
    turned = mobmanip.analyze(paper, _placed(paper, q45, 0.5, 0.5, math.radians(heading_deg)))
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    R = np.array([[c, -s], [s, c]])
    for name in ("kinematic", "dynamic"):
        a, b = base.measures[name], turned.measures[name]
        assert _close(a.semi_axes, b.semi_axes, a.semi_axes[0], RTOL)
        assert _close(R @ a.matrix @ R.T, b.matrix, np.abs(a.matrix).max(), 1e-8)


def _scaled(robot, kind, factor):
    table = robot.joint_velocity_limits if kind == "velocity" else robot.joint_effort_limits
    return robot.with_limits(**{kind: {name: factor * value for name, value in table.items()}})


#: Per kind of limit scaled: the ellipsoid it scales, the one it leaves alone, and the largest
#: limit the robot takes (a factor beyond is refused).
SCALES = {"velocity": ("kinematic", "dynamic", 1e6), "effort": ("dynamic", "kinematic", 1e7)}


@pytest.mark.parametrize("kind", SCALES)
@pytest.mark.parametrize("factor", FACTORS)
def test_limits_scale_their_ellipsoid_and_leave_the_other(paper, q45, kind, factor):
    scaled, other, most = SCALES[kind]
    base = mobmanip.analyze(paper, q45)  # planar: no gravity, the dynamic ellipsoid is centred
    limits = paper.velocity_limits if kind == "velocity" else paper.effort_limits
    try:
        robot = _scaled(paper, kind, factor)
    except RangeError as exc:
        assert "supported range" in str(exc)
        assert factor * limits.max() > most or factor * limits.min() < 1e-6
        return
    result = mobmanip.analyze(robot, q45)
    new, old = result.measures[scaled], base.measures[scaled]
    assert _close(new.semi_axes, factor * old.semi_axes, factor * old.semi_axes[0], RTOL)
    assert _close(new.axes @ old.axes.T, np.diag(np.sign(np.diag(new.axes @ old.axes.T))), 1.0, 1e-8)
    assert np.allclose(result.measures[other].semi_axes, base.measures[other].semi_axes, rtol=RTOL, atol=0)


def test_under_gravity_effort_scaling_keeps_the_centre_and_scales_the_free_part():
    """{a : ||Z (L a + mu)|| <= 1}: with Z -> Z / c the centre (least squares of L a = -mu, in the Z
    norm, which a common factor does not change) stays, and the semi-axes become
    sqrt(c^2 - r^2) / sqrt(1 - r^2) times the old ones, r the part of Z mu no acceleration cancels."""
    robot = mobmanip.load_robot("tiago_dual")
    q = robot.hold_configuration()
    base = mobmanip.analyze(robot, q, "translational", object_mass=1.0)
    dyn0 = base.dynamic
    assert np.linalg.norm(dyn0.center) > 0.1  # gravity shifts it
    terms = mobmanip.MeasureTerms.of(base)
    Z = 1.0 / terms.effort_limits
    # Eq. 33-35 (with the sign of xi that follows from Eq. 28), written out here
    J_pinv, W_pinv, Q_inv = np.linalg.pinv(terms.J_u), np.linalg.pinv(terms.W), np.linalg.inv(terms.Q)
    Lam = Q_inv @ terms.P @ J_pinv @ terms.W.T + Q_inv @ terms.J_u.T @ W_pinv @ terms.M_o
    mu = -Q_inv @ terms.xi + Q_inv @ terms.J_u.T @ W_pinv @ terms.g_o
    A, b = Z[:, None] * Lam, Z * mu
    r = np.linalg.norm(b - A @ np.linalg.lstsq(A, b, rcond=None)[0])
    for factor in (0.5, 3.0, 100.0):
        dyn = mobmanip.analyze(_scaled(robot, "effort", factor), q, "translational", object_mass=1.0).dynamic
        expected = math.sqrt(factor**2 - r**2) / math.sqrt(1.0 - r**2)
        assert np.allclose(dyn.center, dyn0.center, rtol=0, atol=1e-9 * dyn0.semi_axes[0])
        assert _close(dyn.semi_axes, expected * dyn0.semi_axes, expected * dyn0.semi_axes[0], 1e-8)


def _oracle_semi_axes(result, velocity_limits) -> list[float]:
    """Kinematic semi-axes from W (J_hat J_hat^T)^+ W^T in 60-digit arithmetic."""
    mp.mp.dps = 60
    J = mp.matrix(result.unified_jacobian.tolist())
    W = mp.matrix(result.grasp_matrix.tolist())
    J_hat = J * mp.diag([mp.mpf(v) for v in velocity_limits])
    E, V = mp.eigsy(J_hat * J_hat.T)
    largest = max(E)
    G = mp.zeros(J.rows, J.rows)
    for i in range(J.rows):
        if E[i] > largest * mp.mpf(10) ** -40:
            G += V[:, i] * V[:, i].T / E[i]
    return sorted((float(1 / mp.sqrt(e)) for e in mp.eigsy(W * G * W.T)[0]), reverse=True)


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual"])
def test_at_the_largest_supported_ratio_of_limits_the_ellipsoid_is_right(name):
    """Where the ratio check draws its line: wheels as fast as allowed, arms stretched (home) or
    holding (hold), against the same set computed with 60 digits."""
    robot = mobmanip.load_robot(name)
    fastest = 0.99 * LIMIT_RATIO * robot.velocity_limits.min()
    fast = robot.with_wheel_limits(velocity=min(fastest, 1e6))
    for q in (fast.neutral(), fast.hold_configuration()):
        result = mobmanip.analyze(fast, q)
        expected = _oracle_semi_axes(result, fast.velocity_limits)
        assert np.allclose(result.kinematic.semi_axes, expected, rtol=1e-6, atol=0), expected
    with pytest.raises(RangeError, match="supported range"):  # the ratio, or the limit itself
        robot.with_wheel_limits(velocity=1.5 * LIMIT_RATIO * robot.velocity_limits.min())


# ----- API edge cases


@pytest.mark.parametrize("pair", [(3.0, 4.0), (0.0, 0.0), (0.6, 0.8 + 1e-4), (-1e-9, 0.0)])
def test_non_unit_yaw_pairs_are_refused(paper, q45, pair):
    q = q45.copy()
    q[2:4] = pair
    with pytest.raises(ConfigurationError, match="unit vector"):
        mobmanip.analyze(paper, q)
    with pytest.raises(ConfigurationError, match="row 1.*platform yaw"):
        mobmanip.analyze_batch(paper, np.array([q45, q]))
    wheel = paper.model.joints[paper.model.getJointId("wheel_left_joint")]
    q = q45.copy()
    q[wheel.idx_q : wheel.idx_q + 2] = pair
    with pytest.raises(ConfigurationError, match="wheel_left_joint"):
        mobmanip.analyze(paper, q)


def test_unit_pairs_to_rounding_are_accepted(paper, q45):
    q = q45.copy()
    q[2:4] *= 1.0 + 1e-12
    assert np.allclose(mobmanip.analyze(paper, q).kinematic.semi_axes, mobmanip.analyze(paper, q45).kinematic.semi_axes)


@pytest.mark.parametrize("mass", ["2", b"2", [2.0], None if False else {"kg": 2}, True, complex(2, 0), 1e300, -0.0 - 1])
def test_non_numeric_or_out_of_range_masses_are_refused(paper, q45, mass):
    from mobmanip.errors import MobmanipError
    from mobmanip.terms.grasp import HeldObject

    with pytest.raises(MobmanipError, match="mass"):
        mobmanip.analyze(paper, q45, object_mass=mass)
    with pytest.raises(MobmanipError, match="mass"):
        mobmanip.analyze_batch(paper, q45[None, :], object_mass=mass)
    with pytest.raises(MobmanipError, match="mass"):
        HeldObject.between(np.zeros((2, 3)), mass)
