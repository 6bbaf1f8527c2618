"""A mobile base whose planar joints sit on nested bodies (issue 38), as MuJoCo Menagerie's mobile
FR3 Duo writes it: a slide along x on ``virtual_x``, a slide along y on ``virtual_y``, a hinge
about z on the body below. mobmanip reads it as an omnidirectional platform, and its mass matrix,
gravity and hand Jacobian are MuJoCo's own, computed by MuJoCo from the same file.

How the two models map. MuJoCo's velocities are (x', y', theta', joints) with x and y along the
world's axes; mobmanip's platform velocity is (v_x, v_y, omega) in the platform's frame, so
MuJoCo's = T mobmanip's with T = diag(R(theta), 1, I), and M = T^T M_mujoco T, g = T^T g_mujoco,
J = J_mujoco T. The one place the models differ by the reader's stated rule: ``virtual_x``
slides along x only in MuJoCo, and is counted along y too as part of the platform, so its mass
is added to MuJoCo's y-y entry before the comparison (``virtual_y`` slides along both: exact).
Armature (item 3) is in both: every joint's, the platform's included (the slides' as a point mass
on the yaw axis: the same kinetic energy, so the same mass matrix and bias as MuJoCo's).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mjcf_util import mjcf_text, mujoco_terms, platform_map, platform_map_rate
from mobmanip.descriptions import read_description
from mobmanip.robot.detect import detect_spec
from mobmanip.terms.dynamics import mass_matrix

#: The yaw hinge's axis lies at (0.05 + 0.01, 0.02) from the root: mobmanip's platform turns about
#: its root's origin, so the reader moves the body below the root by the opposite.
AXIS = np.array([0.06, 0.02, 0.0])
VIRTUAL_X_MASS = 0.25

#: The base's three joints on nested bodies, armature from a default class, a lift and three arm
#: joints below; ``virtual_x`` weighs VIRTUAL_X_MASS (the fixture checks the file's value).
NESTED = mjcf_text("nested_base")

ARM = ("lift", "j1", "j2", "j3")


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    path = tmp_path_factory.mktemp("nested") / "nested_base.xml"
    path.write_text(NESTED)
    limits = dict.fromkeys(("base_x", "base_y", "base_yaw", *ARM), (1.0, 100.0))
    found = detect_spec(path, ["hand"], limits=limits)
    robot = mobmanip.load_robot(found.spec)
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    assert mj_model.body("virtual_x").mass[0] == VIRTUAL_X_MASS
    return path, found, robot, mj_model


def test_the_nested_planar_joints_are_the_platform_not_arm_or_torso_joints(models):
    path, found, robot, _ = models
    description = read_description(path)
    assert [j.name for j in description.planar_base] == ["planar_x", "planar_y", "planar_theta"]
    assert [j.name for j in description.moving_joints()] == list(ARM)
    assert found.spec.platform == "omnidirectional" and found.spec.torso == ()
    assert found.spec.arms[0].joints == ARM
    assert robot.reduced_velocity_names == ("base_x", "base_y", "base_yaw", *ARM)
    assert any("virtual_x (0.25 kg, slides along x only in MuJoCo)" in note for note in description.notes)
    # the platform chosen explicitly, with --torso: the planar joints are in neither
    explicit = detect_spec(path, ["hand"], platform="omnidirectional", torso=True).spec
    assert explicit.torso == () and explicit.arms[0].joints == ARM


def test_mass_matrix_gravity_bias_and_hand_jacobian_equal_mujocos(models):
    """At rest (gravity) and at random velocities (the bias: Coriolis, centrifugal and gravity,
    where the slides' armature, a point mass on the yaw axis, adds its omega x a v)."""
    _, _, robot, mj_model = models
    assert mj_model.nq == mj_model.nv == 7  # x, y, theta, then the arm
    rng = np.random.default_rng(38)
    model, data = robot.model, robot.model.createData()
    hand = model.getFrameId("hand")
    largest = 0.0
    for _ in range(6):
        x, y, theta = rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-np.pi, np.pi)
        arm = [rng.uniform(*mj_model.jnt_range[mj_model.joint(name).id]) for name in ARM]
        M_mj, g_mj, (J_mj,), (hand_mj,) = mujoco_terms(mj_model, [x, y, theta, *arm], np.zeros(7), ["hand"])
        q = np.array([x + AXIS[0], y + AXIS[1], np.cos(theta), np.sin(theta), *arm])
        T = platform_map(theta, (0, 1, 2), 7, 7)
        T[3:, 3:] = np.eye(4)
        M_mj[1, 1] += VIRTUAL_X_MASS  # the one stated difference (see the module docstring)
        M = mass_matrix(robot, q)
        np.testing.assert_allclose(M, T.T @ M_mj @ T, rtol=0, atol=1e-9)
        np.testing.assert_allclose(pin.computeGeneralizedGravity(model, data, q), T.T @ g_mj, rtol=0, atol=1e-9)
        v = rng.normal(size=7)
        _, bias_mj, _, _ = mujoco_terms(mj_model, [x, y, theta, *arm], T @ v, [])
        # MuJoCo's acceleration is T v' + dT/dt v: its bias seen from the platform's velocities
        expected = T.T @ (bias_mj + M_mj @ platform_map_rate(theta, v, (0, 1, 2), 7))
        np.testing.assert_allclose(pin.nonLinearEffects(model, data, q, v), expected, rtol=0, atol=1e-9)
        J = pin.computeFrameJacobian(model, data, q, hand, pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(J, J_mj @ T, rtol=0, atol=1e-9)
        np.testing.assert_allclose(data.oMf[hand].translation, hand_mj, rtol=0, atol=1e-12)  # x = x_file + AXIS
        largest = max(largest, float(np.abs(M).max()))
    assert largest > 60.0  # the platform's mass is in it


def _root_mass(model) -> float:
    """The root body's mass: the platform's bodies and the planar slides' armature, which
    mobmanip puts on the yaw axis as a point mass (its kinetic energy a/2 |v|^2 in any frame,
    with its gyroscopic term in the bias, as MuJoCo's)."""
    return float(model.inertias[1].mass)


def test_the_platforms_armature_is_in_the_mass_matrix(models):
    _, _, robot, mj_model = models
    np.testing.assert_allclose(robot.model.armature[:3], [0.0, 0.0, 0.05])  # yaw on the joint
    # the slides' on the yaw axis: the root body is base_link (60 kg), the lumped virtual_x, virtual_y and it
    mass = 60 + VIRTUAL_X_MASS + 0.5 + 0.195
    assert _root_mass(robot.model) == pytest.approx(mass, rel=1e-15)
    np.testing.assert_allclose(robot.model.armature[3:], mj_model.dof_armature[3:])  # Pinocchio's reading
    assert mj_model.dof_armature.tolist() == pytest.approx([0.195, 0.195, 0.05, 0.4, 0.195, 0.02, 0.195])


def test_unequal_armature_along_x_and_y_gets_their_mean_with_a_note(tmp_path):
    path = tmp_path / "unequal.xml"
    path.write_text(NESTED.replace('name="planar_y" type="slide"', 'name="planar_y" armature="0.305" type="slide"'))
    description = read_description(path)
    model = description.build_model(pin.JointModelPlanar())
    np.testing.assert_allclose(model.armature[:3], [0.0, 0.0, 0.05])
    assert _root_mass(model) == pytest.approx(60 + VIRTUAL_X_MASS + 0.5 + 0.25, rel=1e-15)
    assert any("both get their mean, 0.25 kg" in note for note in description.notes)


def test_a_chain_that_is_not_a_planar_base_stays_in_the_tree(tmp_path):
    """The yaw hinge above the slides (the slides then move along turning axes): not the
    platform's coordinates, so the joints stay the robot's own."""
    path = tmp_path / "turret.xml"
    text = NESTED.replace('name="planar_theta" axis="0 0 1"', 'name="planar_theta" type="slide" axis="0 0 1"')
    path.write_text(text)
    description = read_description(path)
    assert description.planar_base == ()
    assert [j.name for j in description.moving_joints()][:3] == ["planar_x", "planar_y", "planar_theta"]


#: The planar joints on the root body itself (as TidyBot), armature from the file-wide default
#: and from joints, and a body with two joints (which mobmanip splits into a chain of bodies).
ROOT_BASE = mjcf_text("root_base")


def test_armature_of_every_joint_with_the_base_on_the_root_body_equals_mujocos(tmp_path):
    path = tmp_path / "root_base.xml"
    path.write_text(ROOT_BASE)
    limits = dict.fromkeys(("base_x", "base_y", "base_yaw", "pan", "pitch", "elbow"), (1.0, 100.0))
    robot = mobmanip.load_robot(detect_spec(path, ["hand"], limits=limits).spec)
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    np.testing.assert_allclose(robot.model.armature, [0.0, 0.0, 0.7, 0.3, 0.1, 0.05])
    assert _root_mass(robot.model) == pytest.approx(40 + 0.1, rel=1e-15)  # the slides' 0.1 on the yaw axis
    rng = np.random.default_rng(3)
    for _ in range(4):
        x, y, theta = rng.uniform(-2, 2, 3)
        arm = rng.uniform(-1.5, 1.5, 3)
        data = mujoco.MjData(mj_model)
        data.qpos[:] = [x, y, theta, *arm]
        mujoco.mj_forward(mj_model, data)
        M_mj = np.zeros((6, 6))
        mujoco.mj_fullM(mj_model, data, M_mj)
        T = np.eye(6)
        T[:2, :2] = [[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]]
        q = np.array([x, y, np.cos(theta), np.sin(theta), *arm])
        np.testing.assert_allclose(mass_matrix(robot, q), T.T @ M_mj @ T, rtol=0, atol=1e-9)


def test_a_keyframe_of_the_nested_base_reads_every_joint_as_mujoco_lays_it_out(tmp_path):
    path = tmp_path / "keyed_base.xml"
    key = '<keyframe><key name="stow" qpos="1.5 -0.5 0.3 0.2 1.1 -0.7 0.9"/></keyframe>\n</mujoco>'
    path.write_text(NESTED.replace("</mujoco>", key))
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    expected = {
        mj_model.joint(j).name: float(mj_model.key_qpos[0, mj_model.jnt_qposadr[j]]) for j in range(mj_model.njnt)
    }
    description = read_description(path)
    assert dict(description.keyframes["stow"]) == expected
    assert detect_spec(path, ["hand"]).spec.postures["stow"] == {n: expected[n] for n in ARM}
