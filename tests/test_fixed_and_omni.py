"""Fixed-base arms against the classical ellipsoids, and a holonomic base against the
differential drive carrying the same arms."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from pycapacity.robot import acceleration_ellipsoid, velocity_ellipsoid

import mobmanip
from mobmanip.analysis import analyze
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.motion.carry import ObjectPath, carry


def _same_axes(a: np.ndarray, b: np.ndarray, atol: float) -> None:
    """Rows of a and b are the same unit directions up to sign."""
    for u, v in zip(a, b):
        assert abs(abs(float(u @ v)) - 1.0) < atol


@pytest.fixture(scope="module")
def ur5():
    return mobmanip.load_robot("ur5")


def _ur5_configurations(robot, count=6):
    rng = np.random.default_rng(3)
    names = robot.reduced_velocity_names
    for _ in range(count):
        yield robot.configuration(joints={n: rng.uniform(-2.5, 2.5) for n in names})


def test_ur5_kinematic_ellipsoid_is_the_classical_one(ur5):
    """Radii = singular values of J diag(qdot_max), J the tool frame's own Jacobian (and pycapacity).

    Both sides are SVDs of the same 6x6 product: agreement to 1e-9 relative.
    """
    model, data = ur5.model, ur5.data
    frame = model.getFrameId("tool0")
    for q in _ur5_configurations(ur5):
        J = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)[:, list(ur5.arms[0].v_indices)]
        result = analyze(ur5, q, "spatial", object_mass=0.0).kinematic
        singular = np.linalg.svd(J * ur5.velocity_limits, compute_uv=False)
        np.testing.assert_allclose(result.semi_axes, singular, rtol=1e-9)
        reference = velocity_ellipsoid(J, ur5.velocity_limits)
        order = np.argsort(reference.radii)[::-1]
        np.testing.assert_allclose(result.semi_axes, reference.radii[order], rtol=1e-9)
        _same_axes(result.axes, reference.rotation[:, order].T, atol=1e-7)


def test_ur5_dynamic_ellipsoid_is_the_classical_one_shifted_by_gravity(ur5):
    """{J M^-1 (tau - g) : ||Z tau|| <= 1}: radii/axes from pycapacity, centre -J M^-1 g.

    Square and non-redundant (m = n = 6), so the paper's Lambda = M J^-1 is exact; the UR5's
    joints carry its own weight, so the centre moves. Tolerance 1e-8 relative (conditioning of
    M J^-1 on these configurations is below 1e4).
    """
    model, data = ur5.model, ur5.data
    frame = model.getFrameId("tool0")
    for q in _ur5_configurations(ur5):
        arm = list(ur5.arms[0].v_indices)
        J = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)[:, arm]
        M = pin.crba(model, data, q)
        M = (np.triu(M) + np.triu(M, 1).T)[np.ix_(arm, arm)]
        g = pin.computeGeneralizedGravity(model, data, q)[arm]
        result = analyze(ur5, q, "spatial", object_mass=0.0).dynamic
        assert not result.empty
        reference = acceleration_ellipsoid(J, M, ur5.effort_limits)
        order = np.argsort(reference.radii)[::-1]
        np.testing.assert_allclose(result.semi_axes, reference.radii[order], rtol=1e-8)
        _same_axes(result.axes, reference.rotation[:, order].T, atol=1e-6)
        np.testing.assert_allclose(result.center, -J @ np.linalg.solve(M, g), rtol=1e-8, atol=1e-9)


@pytest.fixture(scope="module")
def pair():
    return mobmanip.load_robot("planar_dual_arm"), mobmanip.load_robot("planar_dual_arm_omni")


def test_matched_omnidirectional_limits(pair):
    """The built-in omni spec's limits follow from the wheels' (comments in the spec), to the last bit."""
    diff, omni = pair
    V = diff.platform.radius * diff.velocity_limits[0]
    b = diff.platform.half_track
    np.testing.assert_allclose(
        omni.velocity_limits[:3], [V / math.sqrt(2), V / math.sqrt(2), V / (math.sqrt(2) * b)], rtol=1e-15
    )
    tau = diff.effort_limits[0]
    r = diff.platform.radius
    np.testing.assert_allclose(
        omni.effort_limits[:3], [math.sqrt(2) * tau / r] * 2 + [math.sqrt(2) * b * tau / r], rtol=1e-15
    )
    np.testing.assert_array_equal(omni.velocity_limits[3:], diff.velocity_limits[2:])


def _same_pose(source, q, target):
    """q of ``source`` expressed for ``target`` (same platform pose and arm joints)."""
    pose = source.configuration_dict(q)
    arm_joints = {name: pose["joints"][name] for name in target.reduced_velocity_names if name in pose["joints"]}
    return target.configuration(tuple(pose["platform"]), arm_joints)


def _directions(n=360):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.stack([np.cos(t), np.sin(t)], axis=1)


@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0])
def test_omnidirectional_contains_differential_drive(pair, angle):
    """Kinematic: the holonomic base can do all the wheels can, so its ellipse contains theirs.

    Support functions compared in 360 directions (relative slack 1e-12 for round-off); at 90
    deg the object lies on the axle line, where the wheels add nothing sideways but the
    holonomic base does, so there the containment is strict along the axle (> 5 %).
    """
    diff, omni = pair
    posture = optimal_posture(diff)
    q = configuration_at(diff, posture, angle)
    wheels = analyze(diff, q, "planar").kinematic
    holonomic = analyze(omni, _same_pose(diff, q, omni), "planar").kinematic
    for d in _directions():
        assert holonomic.support(d) >= wheels.support(d) * (1 - 1e-12)
    if angle == 90.0:
        axle = np.array([0.0, 1.0])
        assert holonomic.radius_along(axle) > 1.05 * wheels.radius_along(axle)


def test_omnidirectional_contains_differential_drive_on_random_configurations(pair):
    diff, omni = pair
    rng = np.random.default_rng(5)
    for _ in range(10):
        joints = {n: rng.uniform(-np.pi, np.pi) for arm in diff.arms for n in arm.joint_names}
        q = diff.configuration((0.0, 0.0, rng.uniform(-np.pi, np.pi)), joints)
        wheels = analyze(diff, q, "planar").kinematic
        holonomic = analyze(omni, _same_pose(diff, q, omni), "planar").kinematic
        for d in _directions(90):
            assert holonomic.support(d) >= wheels.support(d) * (1 - 1e-12)


def test_omnidirectional_carry_along_the_heading_is_the_differential_drives(pair):
    """``carry`` on the holonomic base starts, as on the wheels, from the case-study posture (it
    was refused: its home posture, the arms stretched, is singular). Along a straight path ahead,
    the mirrored arms keep the smallest semi-axis along the heading, where the base's sideways
    column adds nothing: the motion's capacity equals the differential drive's, and the base
    never moves sideways (both to 1e-12)."""
    diff, omni = pair
    t = np.linspace(0.0, 2.0, 21)
    ahead = 0.3 * (3.0 * (t / 2.0) ** 2 - 2.0 * (t / 2.0) ** 3)  # from rest to rest
    path = ObjectPath(t, np.column_stack([ahead, np.zeros_like(t)]))
    wheels, holonomic = (carry(robot, path, prepare=0.0) for robot in pair)
    assert holonomic.start == wheels.start
    assert "case-study posture" in holonomic.start
    for run in ("motion", "baseline"):
        np.testing.assert_allclose(getattr(holonomic, run).capacity, getattr(wheels, run).capacity, rtol=0, atol=1e-12)
    sideways = omni.reduced_velocity_names.index("base_y")
    assert np.max(np.abs(holonomic.motion.x[:, sideways])) < 1e-12
    assert np.min(holonomic.motion.capacity) > 1.0  # the posture is far from singular all along


def test_the_viewers_object_angle_sweep_turns_the_object_on_the_holonomic_base(pair):
    """The viewer's object-angle sweep of the holonomic base is the paper's (it turned the platform
    instead while the posture was the differential drive's only): the object lies at each angle
    from the heading, and at 90 deg, on the axle line, the holonomic ellipse reaches further
    sideways than the wheels' at the same posture."""
    from mobmanip.viz.sweeps import object_angle_frames

    diff, omni = pair
    angles = (0.0, 45.0, 90.0)
    frames = object_angle_frames(omni, angles_deg=angles)
    assert len(frames) == len(angles)
    for frame, angle in zip(frames, angles):
        c = frame.analysis.held_object.center
        assert math.degrees(math.atan2(c[1], c[0])) == pytest.approx(angle, abs=1e-6)
    wheels = analyze(diff, _same_pose(omni, frames[-1].q, diff), "planar").kinematic
    axle = np.array([0.0, 1.0])
    assert frames[-1].analysis.kinematic.radius_along(axle) > 1.05 * wheels.radius_along(axle)
