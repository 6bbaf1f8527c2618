"""The steered (tricycle) platform kind, whose S depends on q: the paper's general constraint
layer (Eq. 10-12) with a non-zero Sdot.

Checked independently of the kind's own formulas: A(q) assembled from Pinocchio's wheel
Jacobians (every wheel's contact point has no horizontal velocity) annihilates S(q) at random
q; Sdot against finite differences of S along the motion through ``pin.integrate``; the
kinetic energy; J_u against central differences; the moving-system xi against RNEA; and the
power balance of the unforced, gravity-free reduced dynamics (the kinetic energy is constant
only with the -S^T M Sdot x term).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.errors import ModelError
from mobmanip.robot.detect import detect_spec

R_DRIVE, R_REAR, WHEELBASE, HALF_TRACK = 0.16, 0.12, 0.9, 0.35


def _box(mass, sx, sy, sz):
    ixx, iyy, izz = (mass / 12 * (b * b + c * c) for b, c in ((sy, sz), (sx, sz), (sx, sy)))
    return (
        f'<inertial><mass value="{mass}"/><inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/>'
        f'</inertial><collision><geometry><box size="{sx} {sy} {sz}"/></geometry></collision>'
    )


def _wheel(name, radius, mass=1.5):
    i_axle, i_other = mass * radius**2 / 2, mass * radius**2 / 4
    return (
        f'<link name="{name}"><inertial><mass value="{mass}"/><inertia ixx="{i_other}" iyy="{i_axle}" '
        f'izz="{i_other}" ixy="0" ixz="0" iyz="0"/></inertial><collision><origin rpy="1.5707963267948966 0 0"/>'
        f'<geometry><cylinder radius="{radius}" length="0.05"/></geometry></collision></link>'
    )


def tricycle_urdf(steer_axis="0 0 1", drive_axis="0 1 0") -> str:
    """A forklift-style tricycle: rear axle at the platform origin, a steered drive wheel
    ahead (offset to the left), a 3-joint arm on top."""
    joints = [
        f'<joint name="rear_right_wheel" type="continuous"><parent link="base_link"/><child link="rr"/>'
        f'<origin xyz="0 {-HALF_TRACK} {R_REAR}"/><axis xyz="0 1 0"/></joint>',
        f'<joint name="rear_left_wheel" type="continuous"><parent link="base_link"/><child link="rl"/>'
        f'<origin xyz="0 {HALF_TRACK} {R_REAR}"/><axis xyz="0 -1 0"/></joint>',
        f'<joint name="steer_joint" type="revolute"><parent link="base_link"/><child link="fork"/>'
        f'<origin xyz="{WHEELBASE} 0.05 {R_DRIVE}"/><axis xyz="{steer_axis}"/>'
        '<limit lower="-1.4" upper="1.4" effort="40" velocity="2.0"/></joint>',
        f'<joint name="drive_wheel" type="continuous"><parent link="fork"/><child link="drive"/>'
        f'<axis xyz="{drive_axis}"/><limit effort="60" velocity="12"/></joint>',
        '<joint name="arm_1" type="revolute"><parent link="base_link"/><child link="l1"/>'
        '<origin xyz="0.4 0 0.5"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="80" velocity="2"/></joint>',
        '<joint name="arm_2" type="revolute"><parent link="l1"/><child link="l2"/>'
        '<origin xyz="0 0 0.2"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="60" velocity="2"/></joint>',
        '<joint name="arm_3" type="revolute"><parent link="l2"/><child link="l3"/>'
        '<origin xyz="0.5 0 0"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="30" velocity="2.5"/>'
        "</joint>",
        '<joint name="tool" type="fixed"><parent link="l3"/><child link="tool_link"/><origin xyz="0.4 0 0"/></joint>',
    ]
    links = [
        f'<link name="base_link">{_box(60.0, 1.2, 0.7, 0.3)}</link>',
        _wheel("rr", R_REAR),
        _wheel("rl", R_REAR),
        f'<link name="fork">{_box(2.0, 0.1, 0.1, 0.2)}</link>',
        _wheel("drive", R_DRIVE, 3.0),
        f'<link name="l1">{_box(4.0, 0.1, 0.1, 0.2)}</link>',
        f'<link name="l2">{_box(3.0, 0.5, 0.08, 0.08)}</link>',
        f'<link name="l3">{_box(2.0, 0.4, 0.06, 0.06)}</link>',
        '<link name="tool_link"/>',
    ]
    return '<robot name="tricycle">' + "".join(links + joints) + "</robot>"


SPEC = """
name = "tricycle"
urdf = "tricycle.urdf"
platform = "steered"
default_task = "translational"
[wheels]
drive = "drive_wheel"
steer = "steer_joint"
rear = ["rear_right_wheel", "rear_left_wheel"]
[[arms]]
name = "arm"
joints = ["arm_1", "arm_2", "arm_3"]
end_effector = "tool_link"
[object]
mass = 1.0
"""


def write_tricycle(directory, **axes):
    (directory / "tricycle.urdf").write_text(tricycle_urdf(**axes))
    (directory / "tricycle.toml").write_text(SPEC)
    return directory / "tricycle.toml"


@pytest.fixture(scope="module", params=[{}, {"steer_axis": "0 0 -1", "drive_axis": "0 -1 0"}], ids=["z", "flipped"])
def tricycle(request, tmp_path_factory):
    return mobmanip.load_robot(write_tricycle(tmp_path_factory.mktemp("tricycle"), **request.param))


def random_state(robot, rng):
    q = robot.configuration(
        tuple(rng.uniform(-2, 2, size=2)) + (rng.uniform(-math.pi, math.pi),),
        {"steer_joint": rng.uniform(-1.2, 1.2), "arm_1": rng.uniform(-2, 2), "arm_2": rng.uniform(-1, 1),
         "arm_3": rng.uniform(-1, 1), "drive_wheel": rng.uniform(-3, 3), "rear_left_wheel": rng.uniform(-3, 3)},
    )  # fmt: skip
    return q, rng.normal(size=robot.nx)


def contact_constraints(robot, q) -> np.ndarray:
    """A(q): horizontal velocity of every wheel's contact point (below its centre), from
    Pinocchio's wheel Jacobians: v_contact = v_centre + omega x (-r e_z)."""
    model, data = robot.model, robot.model.createData()
    pin.computeJointJacobians(model, data, q)
    rows = []
    for name, radius in (("drive_wheel", R_DRIVE), ("rear_right_wheel", R_REAR), ("rear_left_wheel", R_REAR)):
        J = pin.getJointJacobian(model, data, model.getJointId(name), pin.LOCAL_WORLD_ALIGNED)
        down = np.array([0.0, 0.0, -radius])
        contact = J[:3] - np.cross(down, J[3:].T).T  # v + omega x d = v - d x omega
        rows.append(contact[:2])
    return np.vstack(rows)


def test_the_kind_reads_the_geometry(tricycle):
    p = tricycle.platform
    assert p.kind == "steered" and p.varies_with_q
    assert p.wheelbase == pytest.approx(WHEELBASE)
    assert p.radius == pytest.approx(R_DRIVE) and p.rear_radius == pytest.approx(R_REAR)
    assert tricycle.reduced_velocity_names[:2] == ("drive_wheel", "steer_joint")
    np.testing.assert_allclose(tricycle.velocity_limits[:2], (12.0, 2.0))
    np.testing.assert_allclose(tricycle.effort_limits[:2], (60.0, 40.0))
    np.testing.assert_allclose(tricycle.Q, np.eye(tricycle.nx), atol=1e-15)


def test_contact_constraints_annihilate_s_at_random_q(tricycle, rng):
    for _ in range(10):
        q, _ = random_state(tricycle, rng)
        S = tricycle.null_space(q)
        A = contact_constraints(tricycle, q)
        np.testing.assert_allclose(A @ S, 0.0, atol=1e-12)
        # S spans the whole null space of the platform's constraints (nv - rank A directions).
        assert np.linalg.matrix_rank(A, tol=1e-9) + tricycle.nx == tricycle.model.nv
    # and S really depends on q
    q1, _ = random_state(tricycle, rng)
    q2 = q1.copy()
    q2[tricycle.platform.steer_q] += 0.3
    assert np.abs(tricycle.null_space(q1) - tricycle.null_space(q2)).max() > 1e-2


def test_sdot_against_finite_differences_along_the_motion(tricycle, rng):
    for _ in range(5):
        q, x = random_state(tricycle, rng)
        v = tricycle.null_space(q) @ x
        h = 1e-6
        plus = tricycle.null_space(pin.integrate(tricycle.model, q, v * h))
        minus = tricycle.null_space(pin.integrate(tricycle.model, q, -v * h))
        Sdot = tricycle.null_space_rate(q, x)
        assert np.abs(Sdot).max() > 1e-3  # not trivially zero while steering
        np.testing.assert_allclose((plus - minus) / (2 * h), Sdot, atol=1e-8)


def test_kinetic_energy_and_unified_jacobian(tricycle, rng):
    for _ in range(3):
        q, x = random_state(tricycle, rng)
        P = mobmanip.reduced_dynamics(tricycle, q).P
        energy = pin.computeKineticEnergy(tricycle.model, tricycle.data, q, tricycle.null_space(q) @ x)
        assert 0.5 * x @ P @ x == pytest.approx(energy, rel=1e-12)
        J_u = mobmanip.unified_jacobian(tricycle, q, "translational")
        v, h = tricycle.null_space(q) @ x, 1e-6
        tool = tricycle.frame_id("tool_link")

        def tip(qq, frame=tool):
            pin.framesForwardKinematics(tricycle.model, tricycle.data, qq)
            return tricycle.data.oMf[frame].translation.copy()

        numeric = (tip(pin.integrate(tricycle.model, q, v * h)) - tip(pin.integrate(tricycle.model, q, -v * h))) / (
            2 * h
        )
        np.testing.assert_allclose(J_u @ x, numeric, atol=1e-7)


def test_moving_system_xi_against_rnea(tricycle, rng):
    for _ in range(3):
        q, x = random_state(tricycle, rng)
        S, Sdot = tricycle.null_space(q), tricycle.null_space_rate(q, x)
        tau = pin.rnea(tricycle.model, tricycle.model.createData(), q, S @ x, Sdot @ x)
        xi = mobmanip.reduced_dynamics(tricycle, q, x).xi
        np.testing.assert_allclose(xi, -S.T @ tau, atol=1e-9)
        assert np.linalg.norm(Sdot @ x) > 1e-3  # the moving-system term is really there


def test_unforced_reduced_dynamics_conserve_kinetic_energy(tricycle, rng):
    """With no gravity and no torque, P xdot = xi; d/dt (1/2 x^T P x) = x^T P xdot + 1/2 x^T Pdot x
    must vanish (constraint forces do no work). Pdot from central differences along the motion.
    Leaving out the Sdot term of xi breaks it."""
    model = tricycle.model
    gravity = model.gravity.linear.copy()
    model.gravity.linear[:] = 0.0
    try:
        for _ in range(3):
            q, x = random_state(tricycle, rng)
            dyn = mobmanip.reduced_dynamics(tricycle, q, x)
            xdot = np.linalg.solve(dyn.P, dyn.xi)
            v, h = tricycle.null_space(q) @ x, 1e-6
            P_plus = mobmanip.reduced_dynamics(tricycle, pin.integrate(model, q, v * h)).P
            P_minus = mobmanip.reduced_dynamics(tricycle, pin.integrate(model, q, -v * h)).P
            Pdot = (P_plus - P_minus) / (2 * h)
            power = x @ dyn.P @ xdot + 0.5 * x @ Pdot @ x
            scale = abs(0.5 * x @ Pdot @ x) + 1.0
            assert abs(power) < 1e-6 * scale
            # without the Sdot term the balance fails
            S = tricycle.null_space(q)
            xi_static = -S.T @ pin.nonLinearEffects(model, model.createData(), q, v)
            assert abs(x @ xi_static + 0.5 * x @ Pdot @ x) > 1e-3 * scale
    finally:
        model.gravity.linear[:] = gravity


def test_analyze_at_rest_gives_finite_ellipsoids_and_a_moving_platform_helps(tricycle, rng):
    q, _ = random_state(tricycle, rng)
    result = mobmanip.analyze(tricycle, q, task="translational")
    locked = mobmanip.analyze(tricycle.with_platform("fixed"), q, task="translational")
    assert np.all(np.isfinite(result.kinematic.semi_axes))
    assert result.kinematic.volume > locked.kinematic.volume
    exact = mobmanip.analyze(tricycle, q, task="translational", method="exact")
    np.testing.assert_allclose(result.kinematic.semi_axes, exact.kinematic.semi_axes, rtol=1e-10)
    # independently of the analysis: one hand, so W = I and the kinematic semi-axes are the
    # singular values of J_u diag(xdot_max), J_u's columns the tool's central differences
    # along each reduced direction S(q) e_k (S itself checked against the wheels' constraints)
    tool = tricycle.frame_id("tool_link")

    def tip(robot, qq):
        pin.framesForwardKinematics(robot.model, robot.data, qq)
        return robot.data.oMf[tool].translation.copy()

    for robot, measured in ((tricycle, result), (tricycle.with_platform("fixed"), locked)):
        S, h = robot.null_space(q), 1e-6
        J = np.column_stack(
            [
                (
                    tip(robot, pin.integrate(robot.model, q, h * S[:, k]))
                    - tip(robot, pin.integrate(robot.model, q, -h * S[:, k]))
                )
                / (2 * h)
                for k in range(robot.nx)
            ]
        )
        expected = np.linalg.svd(J * robot.velocity_limits, compute_uv=False)
        np.testing.assert_allclose(measured.kinematic.semi_axes, expected, rtol=1e-6)


def test_batches_refuse_a_configuration_dependent_s_by_name(tricycle, rng):
    q, _ = random_state(tricycle, rng)
    with pytest.raises(ModelError, match=r"'tricycle' has a steered platform whose S depends on q"):
        mobmanip.analyze_batch(tricycle, q[None, :], task="translational")


def test_detection_finds_the_tricycle(tmp_path):
    spec_path = write_tricycle(tmp_path)
    found = detect_spec(spec_path.with_suffix(".urdf"), ["tool_link"])
    assert found.spec.platform == "steered"
    assert found.spec.wheels.drive == "drive_wheel" and found.spec.wheels.steer == "steer_joint"
    assert set(found.spec.wheels.rear) == {"rear_right_wheel", "rear_left_wheel"}


def test_null_space_of_a_bad_configuration_or_velocity_is_an_error_naming_it(tricycle):
    from mobmanip.errors import ConfigurationError

    q = tricycle.neutral()
    with pytest.raises(ConfigurationError, match="configuration must have shape"):
        tricycle.null_space(q[:-1])
    with pytest.raises(ConfigurationError, match=f"reduced velocity must be {tricycle.nx} finite numbers"):
        tricycle.null_space_rate(q, np.full(tricycle.nx, np.nan))
