"""The paper's own claims about its case study (Section 4), checked in numbers.

Each claim is one test with its tolerance stated. The set-up is the paper's: two mirrored 3R arms
in their globally optimal posture holding a 2 kg object at 0, 45 and 90 deg from the platform
heading; Fig. 3 varies the wheels' rim speed (0.001, 0.5, 1.0 m/s), Fig. 4 the wheel torque
(200, 50, 10 N m) with decoupled dynamics.
"""

from __future__ import annotations

import numpy as np
import pytest

from mobmanip.analysis import analyze
from mobmanip.casestudy import configuration_at


def kinematic(robot, posture, angle, rim_speed=None):
    """Kinematic ellipse at the object; rim_speed None locks the platform."""
    q = configuration_at(robot, posture, angle)
    if rim_speed is None:
        return analyze(robot.with_platform("fixed"), q, "planar").kinematic
    return analyze(robot.with_wheel_limits(velocity=rim_speed / robot.platform.radius), q, "planar").kinematic


def dynamic(robot, posture, angle, torque, decoupled=True):
    q = configuration_at(robot, posture, angle)
    return analyze(robot.with_wheel_limits(effort=torque), q, "planar", decoupled=decoupled).dynamic


def test_table_parameters_reach_the_model(robot):
    """Tables 1 and 2 as loaded: r, b, limits and the object mass."""
    assert robot.platform.radius == pytest.approx(0.075, abs=0)
    assert robot.platform.half_track == pytest.approx(0.171, abs=0)
    np.testing.assert_allclose(robot.velocity_limits, [1 / 0.075] * 2 + [3.14] * 6, rtol=1e-15)
    np.testing.assert_allclose(robot.effort_limits, [200, 200, 200, 100, 30, 200, 100, 30], rtol=1e-15)
    assert robot.spec.object_mass == 2.0


@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0])
def test_innermost_kinematic_ellipse_is_the_fixed_dual_arm_one(robot, posture, angle):
    """Claim 1 (Fig. 3): at 0.001 m/s the ellipse is almost identical to the fixed dual-arm one.

    The platform adds columns of size 0.001 m/s (forward) and 0.001 / b * reach ~ 0.006 m/s
    (yaw lever) to arm columns of order 1 m/s; squared, they change the semi-axes by a relative
    amount below ~(0.006)^2 / 2 ~ 2e-5. Tolerance 5e-5.
    """
    slow = kinematic(robot, posture, angle, 0.001)
    fixed = kinematic(robot, posture, angle, None)
    np.testing.assert_allclose(slow.semi_axes, fixed.semi_axes, rtol=5e-5)
    for k in range(2):
        assert abs(abs(slow.axes[k] @ fixed.axes[k]) - 1.0) < 1e-6


def test_innermost_ellipse_does_not_depend_on_the_direction(robot, posture):
    """Claim 1, second half: the innermost ellipse has the same shape at every object direction.

    With the platform locked the arms see the object at the same relative posture, so the
    semi-axes agree to round-off (1e-9 relative).
    """
    shapes = [kinematic(robot, posture, a, 0.001).semi_axes for a in (0.0, 45.0, 90.0)]
    np.testing.assert_allclose(shapes[1], shapes[0], rtol=1e-5)
    np.testing.assert_allclose(shapes[2], shapes[0], rtol=1e-5)
    fixed = [kinematic(robot, posture, a, None).semi_axes for a in (0.0, 45.0, 90.0)]
    np.testing.assert_allclose(fixed[1], fixed[0], rtol=1e-9)
    np.testing.assert_allclose(fixed[2], fixed[0], rtol=1e-9)


def test_kinematic_minor_axis_unchanged_sideways(robot, posture):
    """Claim 2 (Fig. 3): at 90 deg the minor axis is the same for all three platform speeds.

    The object lies on the wheel-axle line, along which the platform cannot move it (no lateral
    slip), and by mirror symmetry the minor axis is exactly that direction: equality to round-off
    (1e-9 relative), while the major axis grows.
    """
    ellipses = [kinematic(robot, posture, 90.0, v) for v in (0.001, 0.5, 1.0)]
    minors = np.array([e.semi_axes[1] for e in ellipses])
    np.testing.assert_allclose(minors, minors[0], rtol=1e-9)
    for e in ellipses:  # the minor axis points along the axle (world y at zero heading)
        assert abs(abs(e.axes[1][1]) - 1.0) < 1e-9
    majors = [e.semi_axes[0] for e in ellipses]
    assert majors[0] < majors[1] < majors[2]


def test_kinematic_minor_axis_grows_in_front(robot, posture):
    """Contrast to claim 2: in front (0 deg) the platform does add along the minor axis.

    Forward rolling at 0.5 m/s rim speed adds two columns of 0.25 m/s along the minor axis; the
    minor semi-axis must grow by more than 1 %.
    """
    minors = [kinematic(robot, posture, 0.0, v).semi_axes[1] for v in (0.001, 0.5, 1.0)]
    assert minors[1] > 1.01 * minors[0]
    assert minors[2] > minors[1]


@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0])
def test_faster_platform_never_shrinks_the_kinematic_ellipse(robot, posture, angle):
    """More platform speed only adds motion: each ellipse contains the slower one (support test)."""
    directions = np.stack(
        [np.cos(t) * np.array([1.0, 0]) + np.sin(t) * np.array([0, 1.0]) for t in np.linspace(0, np.pi, 181)]
    )
    previous = kinematic(robot, posture, angle, None)
    for v in (0.001, 0.5, 1.0):
        current = kinematic(robot, posture, angle, v)
        for d in directions:
            assert current.support(d) >= previous.support(d) * (1 - 1e-12)
        previous = current


def test_dynamic_ellipses_at_high_torque_do_not_depend_on_direction(robot, posture):
    """Claim 3 (Fig. 4): with 200 N m the outermost ellipses are the same at 0, 45 and 90 deg.

    Tolerance 2 % on each semi-axis ("almost behaves like a fixed dual-arm system"); as a
    contrast, at 10 N m the major semi-axes differ by more than 10 % between 0 and 90 deg.
    """
    strong = np.array([dynamic(robot, posture, a, 200.0).semi_axes for a in (0.0, 45.0, 90.0)])
    spread = (strong.max(axis=0) - strong.min(axis=0)) / strong.min(axis=0)
    assert np.all(spread < 0.02), spread
    weak = np.array([dynamic(robot, posture, a, 10.0).semi_axes for a in (0.0, 90.0)])
    assert (weak[1, 0] - weak[0, 0]) / weak[0, 0] > 0.10


@pytest.mark.parametrize("decoupled", [True, False])
def test_dynamic_major_axis_unchanged_sideways(robot, posture, decoupled):
    """Claim 4 (Fig. 4): at 90 deg the major axis does not change with the wheel torque.

    Along the axle the wheels cannot accelerate the object, so that semi-axis is set by the arms
    alone: equal to round-off (1e-9 relative) for 200, 50, 10 N m, coupled or decoupled, and it
    is the locked platform's value there.
    """
    ellipses = [dynamic(robot, posture, 90.0, t, decoupled) for t in (200.0, 50.0, 10.0)]
    majors = np.array([e.semi_axes[0] for e in ellipses])
    np.testing.assert_allclose(majors, majors[0], rtol=1e-9)
    for e in ellipses:
        assert abs(abs(e.axes[0][1]) - 1.0) < 1e-9  # along the axle (world y)
    q = configuration_at(robot, posture, 90.0)
    locked = analyze(robot.with_platform("fixed"), q, "planar").dynamic
    along_axle = locked.radius_along(np.array([0.0, 1.0]))
    np.testing.assert_allclose(majors[0], along_axle, rtol=1e-9)


@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0])
def test_dynamic_ellipse_shrinks_as_wheel_torque_drops(robot, posture, angle):
    """Fig. 4: as the wheel torque decreases the ellipse shrinks (area strictly, never grows)."""
    areas = [dynamic(robot, posture, angle, t).volume for t in (200.0, 50.0, 10.0)]
    assert areas[0] > areas[1] > areas[2]


def test_in_front_the_dynamic_ellipse_shrinks_in_both_axes(robot, posture):
    """Fig. 4 at 0 deg: "smaller almost uniformly": both semi-axes shrink from 200 to 10 N m."""
    strong = dynamic(robot, posture, 0.0, 200.0).semi_axes
    weak = dynamic(robot, posture, 0.0, 10.0).semi_axes
    assert np.all(weak < strong)
